//! The packed 8x32 [`Tile`](super::sgemm::Tile) kernel for x86-64 CPUs with
//! AVX2 and FMA but no AVX-512 (AMD before Zen 4, Intel client CPUs).
//!
//! Sixteen 256-bit registers cannot hold an 8x32 tile (32 registers), so the
//! tile is computed as four 4x16 quarters ([`by_quarters`]): eight
//! accumulators, two B vectors and one broadcast A value per step, eight fused
//! multiply-adds to six loads, all from L1.

use std::arch::x86_64::*;

use super::sgemm::{MR, NR};
use super::tile_quarters::by_quarters;

/// The [`Tile`](super::sgemm::Tile) contract.
///
/// # Safety
/// As [`Tile`](super::sgemm::Tile); and the CPU must have AVX2 and FMA.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn tile(
    kc: usize,
    a: *const f32,
    b: *const f32,
    c: *mut f32,
    c_rs: isize,
    load: bool,
    rows: usize,
    cols: usize,
) {
    // SAFETY: forwarded; `quarter` gets what `by_quarters` promises.
    unsafe {
        by_quarters(kc, a, b, c, c_rs, load, rows, cols, |kc, a, b, out| {
            quarter(kc, a, b, out)
        })
    }
}

/// One [`by_quarters`] quarter (a call of its own: its loop is long).
#[target_feature(enable = "avx2,fma")]
unsafe fn quarter(kc: usize, a: *const f32, b: *const f32, out: *mut f32) {
    // Named accumulators: an array makes LLVM spill them inside the loop.
    let z = _mm256_setzero_ps();
    let (mut c00, mut c01, mut c10, mut c11) = (z, z, z, z);
    let (mut c20, mut c21, mut c30, mut c31) = (z, z, z, z);
    let (mut ap, mut bp) = (a, b);
    for _ in 0..kc {
        // SAFETY: the caller's strips hold kc steps of MR and NR values.
        unsafe {
            let b0 = _mm256_loadu_ps(bp);
            let b1 = _mm256_loadu_ps(bp.add(8));
            macro_rules! row {
                ($r:expr, $x:ident, $y:ident) => {
                    let ar = _mm256_broadcast_ss(&*ap.add($r));
                    $x = _mm256_fmadd_ps(ar, b0, $x);
                    $y = _mm256_fmadd_ps(ar, b1, $y);
                };
            }
            row!(0, c00, c01);
            row!(1, c10, c11);
            row!(2, c20, c21);
            row!(3, c30, c31);
            ap = ap.add(MR);
            bp = bp.add(NR);
        }
    }
    for (r, (x, y)) in [(c00, c01), (c10, c11), (c20, c21), (c30, c31)]
        .into_iter()
        .enumerate()
    {
        // SAFETY: out addresses 4 rows of 16 with row stride NR.
        unsafe {
            _mm256_storeu_ps(out.add(r * NR), x);
            _mm256_storeu_ps(out.add(r * NR + 8), y);
        }
    }
}
