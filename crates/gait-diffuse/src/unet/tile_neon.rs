//! The packed 8x32 [`Tile`](super::sgemm::Tile) kernel for aarch64 (NEON, on
//! every aarch64 CPU: Apple Silicon, Graviton, Ampere).
//!
//! Computed as four 4x16 quarters ([`by_quarters`]): sixteen 128-bit
//! accumulators, four B vectors and one A vector per step, whose four lanes
//! feed sixteen lane-indexed fused multiply-adds (`fmla v.4s, v.4s, v.s[i]`),
//! 21 of the 32 registers.

use std::arch::aarch64::*;

use super::sgemm::{MR, NR};
use super::tile_quarters::by_quarters;

/// The [`Tile`](super::sgemm::Tile) contract.
///
/// # Safety
/// As [`Tile`](super::sgemm::Tile); and the CPU must have NEON.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "neon")]
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
#[target_feature(enable = "neon")]
unsafe fn quarter(kc: usize, a: *const f32, b: *const f32, out: *mut f32) {
    let z = vdupq_n_f32(0.0);
    // Named accumulators, row r, columns 4j..4j+4.
    let (mut c00, mut c01, mut c02, mut c03) = (z, z, z, z);
    let (mut c10, mut c11, mut c12, mut c13) = (z, z, z, z);
    let (mut c20, mut c21, mut c22, mut c23) = (z, z, z, z);
    let (mut c30, mut c31, mut c32, mut c33) = (z, z, z, z);
    let (mut ap, mut bp) = (a, b);
    for _ in 0..kc {
        // SAFETY: the caller's strips hold kc steps of MR and NR values.
        unsafe {
            let av = vld1q_f32(ap);
            let (b0, b1) = (vld1q_f32(bp), vld1q_f32(bp.add(4)));
            let (b2, b3) = (vld1q_f32(bp.add(8)), vld1q_f32(bp.add(12)));
            macro_rules! row {
                ($lane:literal, $w:ident, $x:ident, $y:ident, $z:ident) => {
                    $w = vfmaq_laneq_f32::<$lane>($w, b0, av);
                    $x = vfmaq_laneq_f32::<$lane>($x, b1, av);
                    $y = vfmaq_laneq_f32::<$lane>($y, b2, av);
                    $z = vfmaq_laneq_f32::<$lane>($z, b3, av);
                };
            }
            row!(0, c00, c01, c02, c03);
            row!(1, c10, c11, c12, c13);
            row!(2, c20, c21, c22, c23);
            row!(3, c30, c31, c32, c33);
            ap = ap.add(MR);
            bp = bp.add(NR);
        }
    }
    let rows = [
        [c00, c01, c02, c03],
        [c10, c11, c12, c13],
        [c20, c21, c22, c23],
        [c30, c31, c32, c33],
    ];
    for (r, row) in rows.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            // SAFETY: out addresses 4 rows of 16 with row stride NR.
            unsafe { vst1q_f32(out.add(r * NR + 4 * j), *v) };
        }
    }
}
