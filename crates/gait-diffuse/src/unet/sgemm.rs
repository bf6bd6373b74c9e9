//! An f32 matrix product for x86-64 CPUs with AVX-512, the inner loop of the
//! UNet's convolutions, linear layers and attention. On this project's AMD
//! EPYC (Zen 4) machines the `gemm` crate reached 28 GFLOP/s per thread where
//! torch's MKL reaches 33-49 (BENCHMARKS.md); this is the classic packed
//! layout (Goto & van de Geijn): panels of B and A are copied into the order
//! an 8x32 register tile reads them, so the inner loop is one broadcast and
//! two fused multiply-adds per row and step. Other CPUs, and products
//! narrower than 64, keep `gemm` (see `cpu::matmul`).

use rayon::prelude::*;

use super::cpu::{self, SharedMut, View};

/// Register tile: rows of A (broadcast) and columns of B (two 16-wide vectors).
pub(crate) const MR: usize = 8;
pub(crate) const NR: usize = 32;
/// Depth of one packed panel: a B micro-panel (KC x NR) stays in the 32 KiB L1.
const KC: usize = 192;
/// Rows of A packed at a time (KC x MC floats, ~200 KiB, in L2).
const MC: usize = 256;
/// Columns of B packed at a time (KC x NC floats, ~3 MiB, in L3).
const NC: usize = 4096;

/// True when this CPU has a vector [`Tile`] kernel, so [`sgemm`] beats `gemm`.
pub(crate) fn available() -> bool {
    vector_tile().is_some()
}

/// The tile kernel for this CPU's widest vectors, if we have one.
fn vector_tile() -> Option<Tile> {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") {
            return Some(tile_avx512);
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            return Some(super::tile_avx2::tile);
        }
    }
    #[cfg(target_arch = "aarch64")]
    if std::arch::is_aarch64_feature_detected!("neon") {
        return Some(super::tile_neon::tile);
    }
    None
}

/// `dst (m x n, row stride dst_rs) = [dst +] lhs (m x k) @ rhs (k x n)`,
/// split over `threads` rayon tasks.
///
/// # Safety
/// As `cpu::matmul`; and [`available`] must be true.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn sgemm(
    (m, n, k): (usize, usize, usize),
    dst: *mut f32,
    dst_rs: isize,
    accumulate: bool,
    lhs: View,
    rhs: View,
    threads: usize,
) {
    if m == 0 || n == 0 {
        return;
    }
    // Split the longer side into one part per thread, on tile boundaries.
    let split_n = n >= m;
    let (len, unit) = if split_n { (n, NR) } else { (m, MR) };
    let parts = threads.clamp(1, len.div_ceil(unit).max(1));
    let step = len.div_ceil(parts).div_ceil(unit) * unit;
    let dst = SharedMut(dst);
    let run = |part: usize| {
        let (lo, hi) = (part * step, ((part + 1) * step).min(len));
        if lo >= hi {
            return;
        }
        // SAFETY: each part writes its own rows or columns of dst; the views
        // are offset inside the caller's extents.
        unsafe {
            let (shape, dst, lhs, rhs) = if split_n {
                let rhs = View {
                    ptr: rhs.ptr.offset(lo as isize * rhs.cs),
                    ..rhs
                };
                ((m, hi - lo, k), dst.get().add(lo), lhs, rhs)
            } else {
                let lhs = View {
                    ptr: lhs.ptr.offset(lo as isize * lhs.rs),
                    ..lhs
                };
                (
                    (hi - lo, n, k),
                    dst.get().offset(lo as isize * dst_rs),
                    lhs,
                    rhs,
                )
            };
            single(shape, dst, dst_rs, accumulate, lhs, rhs);
        }
    };
    if parts == 1 {
        run(0);
    } else {
        (0..parts).into_par_iter().for_each(run);
    }
}

/// One thread's product (same contract as [`sgemm`]).
unsafe fn single(
    (m, n, k): (usize, usize, usize),
    dst: *mut f32,
    dst_rs: isize,
    accumulate: bool,
    lhs: View,
    rhs: View,
) {
    // Packing buffers come from the thread's scratch pool: attention calls
    // this thousands of times per layer, and fresh pages cost a fault each.
    let kc_max = KC.min(k).max(1);
    let bp_len = kc_max * NC.min(n.div_ceil(NR) * NR);
    let ap_len = kc_max * MC.min(m.div_ceil(MR) * MR);
    let tile = tile_kernel();
    cpu::with_scratch(bp_len, |bp| {
        cpu::with_scratch(ap_len, |ap| {
            for jc in (0..n).step_by(NC) {
                let nc = NC.min(n - jc);
                if k == 0 && !accumulate {
                    for i in 0..m {
                        // SAFETY: row i, columns jc..jc+nc of dst.
                        unsafe {
                            std::slice::from_raw_parts_mut(
                                dst.offset(i as isize * dst_rs).add(jc),
                                nc,
                            )
                        }
                        .fill(0.0);
                    }
                }
                for pc in (0..k).step_by(KC) {
                    let kc = KC.min(k - pc);
                    // SAFETY: the caller's views cover k x n and m x k.
                    unsafe { pack::<NR>(bp, rhs, pc, kc, jc, nc) };
                    for ic in (0..m).step_by(MC) {
                        let mc = MC.min(m - ic);
                        unsafe { pack_a(ap, lhs, ic, mc, pc, kc) };
                        let load = accumulate || pc > 0;
                        for jr in (0..nc).step_by(NR) {
                            let b = &bp[jr * kc..];
                            for ir in (0..mc).step_by(MR) {
                                let a = &ap[ir * kc..];
                                let c =
                                    unsafe { dst.offset((ic + ir) as isize * dst_rs).add(jc + jr) };
                                let (rows, cols) = (MR.min(mc - ir), NR.min(nc - jr));
                                // SAFETY: a and b hold kc full MR / NR strips (zero
                                // padded); c addresses rows x cols of dst.
                                unsafe {
                                    tile(kc, a.as_ptr(), b.as_ptr(), c, dst_rs, load, rows, cols)
                                };
                            }
                        }
                    }
                }
            }
        })
    })
}

/// Copies `lhs[ic..ic+mc, pc..pc+kc]` into MR-tall strips, `ap[strip][p][r]`:
/// the same packing as B's, of A's transpose.
unsafe fn pack_a(ap: &mut [f32], lhs: View, ic: usize, mc: usize, pc: usize, kc: usize) {
    let lhs_t = View {
        ptr: lhs.ptr,
        rs: lhs.cs,
        cs: lhs.rs,
    };
    // SAFETY: forwarded.
    unsafe { pack::<MR>(ap, lhs_t, pc, kc, ic, mc) }
}

/// Copies the `kc x nc` block of `src` at `(p0, j0)` into strips `W` wide,
/// `buf[strip][p][j]`, zero past column `nc` (B's panels directly, A's
/// through [`pack_a`]).
///
/// # Safety
/// `src` must address the whole block.
pub(crate) unsafe fn pack<const W: usize>(
    buf: &mut [f32],
    src: View,
    p0: usize,
    kc: usize,
    j0: usize,
    nc: usize,
) {
    for (s, strip) in buf
        .chunks_exact_mut(kc * W)
        .take(nc.div_ceil(W))
        .enumerate()
    {
        let cols = W.min(nc - s * W);
        // SAFETY: (p0 + p, j0 + s*W + j) is inside src for p < kc, j < cols.
        let at = |p: usize, j: usize| unsafe {
            src.ptr
                .offset((p0 + p) as isize * src.rs + (j0 + s * W + j) as isize * src.cs)
        };
        if src.cs == 1 {
            for (p, row) in strip.chunks_exact_mut(W).enumerate() {
                row[..cols].copy_from_slice(unsafe { std::slice::from_raw_parts(at(p, 0), cols) });
                row[cols..].fill(0.0);
            }
        } else if src.rs == 1 && cols == W {
            // Columns are contiguous: read the W of them side by side so the
            // writes go in order.
            let col: [&[f32]; W] =
                std::array::from_fn(|j| unsafe { std::slice::from_raw_parts(at(0, j), kc) });
            for (p, out) in strip.chunks_exact_mut(W).enumerate() {
                for (o, c) in out.iter_mut().zip(&col) {
                    *o = c[p];
                }
            }
        } else {
            for (p, out) in strip.chunks_exact_mut(W).enumerate() {
                for (j, o) in out.iter_mut().enumerate() {
                    *o = if j < cols {
                        unsafe { at(p, j).read_unaligned() }
                    } else {
                        0.0
                    };
                }
            }
        }
    }
}

/// A tile kernel: `c (rows x cols) = [c +] a-strip @ b-strip` for one packed
/// MR x NR tile, arguments `(kc, a, b, c, c_rs, load, rows, cols)`: `a` holds
/// `kc` x MR values (`a[p * MR + r]`), `b` `kc` x NR (`b[p * NR + j]`), both
/// zero past `rows` / `cols`; `c` addresses rows x cols with row stride
/// `c_rs`, added to when `load`.
pub(crate) type Tile =
    unsafe fn(usize, *const f32, *const f32, *mut f32, isize, bool, usize, usize);

/// This CPU's tile kernel: AVX-512, AVX2+FMA or NEON where the CPU has them,
/// else plain code the compiler vectorises for the baseline target. Callers
/// look it up once per product, not per tile.
pub(crate) fn tile_kernel() -> Tile {
    vector_tile().unwrap_or(tile_portable)
}

/// The [`Tile`] kernel in plain code.
#[allow(clippy::too_many_arguments)]
unsafe fn tile_portable(
    kc: usize,
    a: *const f32,
    b: *const f32,
    c: *mut f32,
    c_rs: isize,
    load: bool,
    rows: usize,
    cols: usize,
) {
    let mut acc = [0f32; MR * NR];
    // SAFETY: the strips hold kc x MR and kc x NR values.
    let (a, b) = unsafe {
        (
            std::slice::from_raw_parts(a, kc * MR),
            std::slice::from_raw_parts(b, kc * NR),
        )
    };
    for (ap, bp) in a.chunks_exact(MR).zip(b.chunks_exact(NR)) {
        for (row, &ar) in acc.chunks_exact_mut(NR).zip(ap) {
            row.iter_mut().zip(bp).for_each(|(o, &bv)| *o += ar * bv);
        }
    }
    // SAFETY: forwarded.
    unsafe { store_part(&acc, c, c_rs, load, rows, cols) }
}

/// The [`Tile`] kernel with AVX-512 registers.
#[allow(clippy::too_many_arguments)]
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn tile_avx512(
    kc: usize,
    a: *const f32,
    b: *const f32,
    c: *mut f32,
    c_rs: isize,
    load: bool,
    rows: usize,
    cols: usize,
) {
    use std::arch::x86_64::*;
    // Sixteen named accumulators: with an array LLVM shuffled and spilled
    // them inside the loop (perf annotate), costing a third of the speed.
    let z = _mm512_setzero_ps();
    let (mut c00, mut c01, mut c10, mut c11, mut c20, mut c21, mut c30, mut c31) =
        (z, z, z, z, z, z, z, z);
    let (mut c40, mut c41, mut c50, mut c51, mut c60, mut c61, mut c70, mut c71) =
        (z, z, z, z, z, z, z, z);
    let (mut ap, mut bp) = (a, b);
    for _ in 0..kc {
        // SAFETY: the strips hold kc x MR and kc x NR values.
        unsafe {
            let b0 = _mm512_loadu_ps(bp);
            let b1 = _mm512_loadu_ps(bp.add(16));
            macro_rules! row {
                ($r:expr, $x:ident, $y:ident) => {
                    let ar = _mm512_set1_ps(*ap.add($r));
                    $x = _mm512_fmadd_ps(ar, b0, $x);
                    $y = _mm512_fmadd_ps(ar, b1, $y);
                };
            }
            row!(0, c00, c01);
            row!(1, c10, c11);
            row!(2, c20, c21);
            row!(3, c30, c31);
            row!(4, c40, c41);
            row!(5, c50, c51);
            row!(6, c60, c61);
            row!(7, c70, c71);
            ap = ap.add(MR);
            bp = bp.add(NR);
        }
    }
    let acc = [
        [c00, c01],
        [c10, c11],
        [c20, c21],
        [c30, c31],
        [c40, c41],
        [c50, c51],
        [c60, c61],
        [c70, c71],
    ];
    if rows == MR && cols == NR {
        for (r, acc) in acc.iter().enumerate() {
            // SAFETY: a full tile of c.
            unsafe {
                let row = c.offset(r as isize * c_rs);
                let (mut v0, mut v1) = (acc[0], acc[1]);
                if load {
                    v0 = _mm512_add_ps(v0, _mm512_loadu_ps(row));
                    v1 = _mm512_add_ps(v1, _mm512_loadu_ps(row.add(16)));
                }
                _mm512_storeu_ps(row, v0);
                _mm512_storeu_ps(row.add(16), v1);
            }
        }
        return;
    }
    let mut tmp = [0f32; MR * NR];
    for (r, acc) in acc.iter().enumerate() {
        // SAFETY: tmp holds MR x NR.
        unsafe {
            _mm512_storeu_ps(tmp.as_mut_ptr().add(r * NR), acc[0]);
            _mm512_storeu_ps(tmp.as_mut_ptr().add(r * NR + 16), acc[1]);
        }
    }
    // SAFETY: forwarded.
    unsafe { store_part(&tmp, c, c_rs, load, rows, cols) }
}

/// Rows x cols of an MR x NR tile `tmp` into `c` (the ragged edges).
///
/// # Safety
/// `c` must address rows x cols with row stride `c_rs`.
pub(crate) unsafe fn store_part(
    tmp: &[f32; MR * NR],
    c: *mut f32,
    c_rs: isize,
    load: bool,
    rows: usize,
    cols: usize,
) {
    for r in 0..rows {
        // SAFETY: rows x cols of c.
        let row = unsafe { std::slice::from_raw_parts_mut(c.offset(r as isize * c_rs), cols) };
        for (d, v) in row.iter_mut().zip(&tmp[r * NR..r * NR + cols]) {
            *d = if load { *d + v } else { *v };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every tile kernel this CPU can run, by name.
    fn kernels() -> Vec<(&'static str, Tile)> {
        let mut k: Vec<(&'static str, Tile)> = vec![("portable", tile_portable)];
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx512f") {
                k.push(("avx512", tile_avx512));
            }
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                k.push(("avx2", super::super::tile_avx2::tile));
            }
        }
        #[cfg(target_arch = "aarch64")]
        if std::arch::is_aarch64_feature_detected!("neon") {
            k.push(("neon", super::super::tile_neon::tile));
        }
        k
    }

    #[test]
    fn every_tile_matches_a_naive_product_on_full_and_ragged_tiles() {
        let names: Vec<_> = kernels().iter().map(|k| k.0).collect();
        eprintln!("tile kernels on this CPU: {names:?}");
        for (name, f) in kernels() {
            for (kc, rows, cols, load) in [
                (37, 5, 19, true),
                (192, MR, NR, false),
                (64, MR, NR, true),
                (1, 3, 17, false),
                (9, MR, 7, true),
            ] {
                let a: Vec<f32> = (0..kc * MR).map(|i| ((i * 7) % 13) as f32 - 6.0).collect();
                let b: Vec<f32> = (0..kc * NR).map(|i| ((i * 5) % 11) as f32 - 5.0).collect();
                // Zero past rows / cols, as packing leaves the strips.
                let a: Vec<f32> = a
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| if i % MR < rows { v } else { 0.0 })
                    .collect();
                let b: Vec<f32> = b
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| if i % NR < cols { v } else { 0.0 })
                    .collect();
                let c_rs = NR as isize + 3;
                let mut c = vec![1f32; (rows + 1) * c_rs as usize];
                unsafe {
                    f(
                        kc,
                        a.as_ptr(),
                        b.as_ptr(),
                        c.as_mut_ptr(),
                        c_rs,
                        load,
                        rows,
                        cols,
                    );
                }
                for r in 0..=rows {
                    for j in 0..c_rs as usize {
                        let want = if r < rows && j < cols {
                            let dot = (0..kc).map(|p| a[p * MR + r] * b[p * NR + j]).sum::<f32>();
                            if load { 1.0 + dot } else { dot }
                        } else {
                            1.0
                        };
                        assert_eq!(c[r * c_rs as usize + j], want, "{name} kc {kc} ({r}, {j})");
                    }
                }
            }
        }
    }

    #[test]
    fn matches_a_naive_product_on_ragged_shapes_strides_and_threads() {
        if !available() {
            eprintln!("no vector tile kernel on this CPU: sgemm is not used here");
            return;
        }
        let shapes = [
            (1, 1, 1),
            (3, 5, 7),
            (9, 33, 200),
            (17, 70, 400),
            (260, 40, 5),
            (8, 32, 0),
        ];
        // Layout 0: row-major; 1: transposed (column-major); 2: every other
        // element of a row-major matrix twice as wide (neither stride is 1).
        let view = |v: &[f32], rows: usize, cols: usize, layout: usize| match layout {
            0 => View {
                ptr: v.as_ptr(),
                rs: cols as isize,
                cs: 1,
            },
            1 => View {
                ptr: v.as_ptr(),
                rs: 1,
                cs: rows as isize,
            },
            _ => View {
                ptr: v.as_ptr(),
                rs: 2 * cols as isize,
                cs: 2,
            },
        };
        let index = |i: usize, j: usize, rows: usize, cols: usize, layout: usize| match layout {
            0 => i * cols + j,
            1 => j * rows + i,
            _ => 2 * (i * cols + j),
        };
        for (m, n, k) in shapes {
            for (threads, accumulate, layout) in [(1, false, 0), (2, true, 1), (3, false, 2)] {
                let a: Vec<f32> = (0..2 * m * k)
                    .map(|i| ((i * 7) % 13) as f32 - 6.0)
                    .collect();
                let b: Vec<f32> = (0..2 * k * n)
                    .map(|i| ((i * 5) % 11) as f32 - 5.0)
                    .collect();
                let (lhs, rhs) = (view(&a, m, k, layout), view(&b, k, n, layout));
                let mut c: Vec<f32> = (0..m * n).map(|i| (i % 3) as f32).collect();
                let c0 = c.clone();
                unsafe {
                    sgemm(
                        (m, n, k),
                        c.as_mut_ptr(),
                        n as isize,
                        accumulate,
                        lhs,
                        rhs,
                        threads,
                    )
                };
                for i in 0..m {
                    for j in 0..n {
                        let mut s = if accumulate { c0[i * n + j] } else { 0.0 };
                        for p in 0..k {
                            s += a[index(i, p, m, k, layout)] * b[index(p, j, k, n, layout)];
                        }
                        assert_eq!(
                            c[i * n + j],
                            s,
                            "{m}x{n}x{k} layout {layout} threads {threads} at ({i}, {j})"
                        );
                    }
                }
            }
        }
    }
}
