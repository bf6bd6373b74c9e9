//! An 8x32 [`Tile`](super::sgemm::Tile) computed as 4x16 quarters, for
//! vector units with too few registers to hold the whole tile (AVX2's sixteen
//! 256-bit and NEON's thirty-two 128-bit registers). The packed layout stays
//! the AVX-512 kernel's, so packing, attention and the tests are shared.

use super::sgemm::{MR, NR, store_part};

/// Rows and columns of one quarter.
pub(crate) const QR: usize = 4;
pub(crate) const QC: usize = 16;

/// Runs `quarter(kc, a, b, out)` on each quarter that holds rows below `rows`
/// and columns below `cols`: it must write `out (QR x QC, row stride NR) =
/// a-strip rows @ b-strip columns` over `kc` steps, `a` and `b` pointing at
/// the quarter's first row and column. Then stores the tile as [`Tile`] does.
/// Inlined into each kernel, so the quarter's intrinsics are too.
///
/// # Safety
/// As [`Tile`](super::sgemm::Tile).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) unsafe fn by_quarters(
    kc: usize,
    a: *const f32,
    b: *const f32,
    c: *mut f32,
    c_rs: isize,
    load: bool,
    rows: usize,
    cols: usize,
    quarter: impl Fn(usize, *const f32, *const f32, *mut f32),
) {
    let mut tmp = [0f32; MR * NR];
    for r0 in (0..rows).step_by(QR) {
        for c0 in (0..cols).step_by(QC) {
            // SAFETY: the strips hold kc x MR and kc x NR values, zero past
            // rows / cols; the quarter at (r0, c0) lies inside the MR x NR tmp.
            quarter(kc, unsafe { a.add(r0) }, unsafe { b.add(c0) }, unsafe {
                tmp.as_mut_ptr().add(r0 * NR + c0)
            });
        }
    }
    // SAFETY: forwarded.
    unsafe { store_part(&tmp, c, c_rs, load, rows, cols) }
}
