//! Access to the f32 buffers of contiguous CPU tensors, the one matrix
//! product all our CPU kernels are built on, and a vectorisable `exp`.
//! The kernels in this folder use these when their inputs are f32 on the CPU;
//! every other case goes through candle's ops.

use candle_core::{CpuStorage, DType, Device, Result, Storage, Tensor};

/// True when `t` is an f32 tensor on the CPU (the fast kernels' domain).
pub(crate) fn is_cpu_f32(t: &Tensor) -> bool {
    t.dtype() == DType::F32 && t.device().is_cpu()
}

/// Runs `f` on the f32 values of `t` in row-major order (copying only when
/// `t` is a strided view).
pub(crate) fn with_f32<R>(t: &Tensor, f: impl FnOnce(&[f32]) -> Result<R>) -> Result<R> {
    let t = t.contiguous()?;
    let (storage, layout) = t.storage_and_layout();
    let Storage::Cpu(CpuStorage::F32(data)) = &*storage else {
        candle_core::bail!("expected an f32 CPU tensor, got {:?}", t.dtype());
    };
    let Some((start, end)) = layout.contiguous_offsets() else {
        candle_core::bail!("tensor is not contiguous after contiguous()");
    };
    f(&data[start..end])
}

/// An f32 CPU tensor owning `data`.
pub(crate) fn tensor(data: Vec<f32>, shape: &[usize]) -> Result<Tensor> {
    Tensor::from_vec(data, shape, &Device::Cpu)
}

/// A raw pointer that rayon tasks writing disjoint parts of one buffer share.
#[derive(Clone, Copy)]
pub(crate) struct SharedMut(pub *mut f32);
// SAFETY: every user writes a region no other task touches.
unsafe impl Send for SharedMut {}
unsafe impl Sync for SharedMut {}

impl SharedMut {
    /// The pointer (a method, so closures capture the whole Sync wrapper).
    pub fn get(self) -> *mut f32 {
        self.0
    }
}

/// A strided matrix view: element (i, j) at `ptr + i * rs + j * cs`.
#[derive(Clone, Copy)]
pub(crate) struct View {
    pub ptr: *const f32,
    pub rs: isize,
    pub cs: isize,
}
// SAFETY: a view only reads, and the products that take one (whose callers
// guarantee the memory stays valid) return before it goes out of scope.
unsafe impl Send for View {}
unsafe impl Sync for View {}

/// `dst (m x n) = [dst +] lhs (m x k) @ rhs (k x n)`, on all threads when
/// `parallel` (the caller is not already inside a parallel loop).
///
/// # Safety
/// Every view must address valid memory for its whole (m|k) x (k|n) extent
/// and `dst` must not overlap the inputs.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn matmul(
    (m, n, k): (usize, usize, usize),
    dst: *mut f32,
    dst_rs: isize,
    accumulate: bool,
    lhs: View,
    rhs: View,
    parallel: bool,
) {
    let threads = if parallel {
        candle_core::utils::get_num_threads()
    } else {
        1
    };
    // The packed kernel pays for its copies once both sides are wide.
    if m >= 64 && n >= 64 && super::sgemm::available() {
        // SAFETY: forwarded from the caller.
        unsafe { super::sgemm::sgemm((m, n, k), dst, dst_rs, accumulate, lhs, rhs, threads) };
        return;
    }
    let par = if threads > 1 {
        gemm::Parallelism::Rayon(candle_core::utils::get_num_threads())
    } else {
        gemm::Parallelism::None
    };
    // SAFETY: forwarded from the caller.
    unsafe {
        gemm::gemm(
            m, n, k, dst, 1, dst_rs, accumulate, lhs.ptr, lhs.cs, lhs.rs, rhs.ptr, rhs.cs, rhs.rs,
            1.0, 1.0, false, false, false, par,
        )
    }
}

thread_local! {
    /// Work buffers kept between calls: the convolutions' buffers are tens of
    /// MB, and fresh ones cost a page fault per 4 KiB on every call.
    static SCRATCH: std::cell::RefCell<Vec<Vec<f32>>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs `f` on a work buffer of `len` values with unspecified contents
/// (reused from earlier calls on this thread; `f` must write before reading).
pub(crate) fn with_scratch<R>(len: usize, f: impl FnOnce(&mut [f32]) -> R) -> R {
    let mut buf = SCRATCH.with(|s| s.borrow_mut().pop()).unwrap_or_default();
    if buf.len() < len {
        buf.resize(len, 0.0);
    }
    let out = f(&mut buf[..len]);
    SCRATCH.with(|s| s.borrow_mut().push(buf));
    out
}

/// `exp(x)` (clamped to [-87.3, 88]), within a few ulp (Cephes' `expf` reduction and
/// polynomial), written without branches so loops over it vectorise.
#[inline(always)]
pub(crate) fn exp(x: f32) -> f32 {
    let x = x.clamp(-87.3, 88.0);
    // Round to nearest by the 1.5 * 2^23 trick: `floor` is a libm call on
    // the baseline x86-64 target and would keep loops over `exp` scalar.
    let k = (x * std::f32::consts::LOG2_E + 12_582_912.0) - 12_582_912.0;
    // ln 2 split in two so k * ln2 is exact enough.
    let r = x - k * 0.693_359_4 + k * 2.121_944_4e-4;
    let z = r * r;
    let p = ((((1.987_569_1e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 0.5;
    let y = p * z + r + 1.0;
    // SAFETY: the clamp keeps k in [-126, 127], so the conversion is exact
    // (and, unlike `as`, free of the saturation checks that stop vectorising).
    let e = unsafe { k.to_int_unchecked::<i32>() };
    y * f32::from_bits(((e + 127) << 23) as u32)
}

/// [`exp`] on 16 lanes.
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
pub(crate) unsafe fn exp_avx512(x: std::arch::x86_64::__m512) -> std::arch::x86_64::__m512 {
    use std::arch::x86_64::*;
    let c = _mm512_set1_ps;
    let x = _mm512_min_ps(_mm512_max_ps(x, c(-87.3)), c(88.0));
    let k = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(_mm512_fmadd_ps(
        x,
        c(std::f32::consts::LOG2_E),
        c(0.5),
    ));
    let r = _mm512_fnmadd_ps(k, c(0.693_359_4), x);
    let r = _mm512_fmadd_ps(k, c(2.121_944_4e-4), r);
    let mut p = c(1.987_569_1e-4);
    for coef in [
        1.398_199_9e-3,
        8.333_452e-3,
        4.166_579_6e-2,
        1.666_666_5e-1,
        0.5,
    ] {
        p = _mm512_fmadd_ps(p, r, c(coef));
    }
    let y = _mm512_add_ps(_mm512_fmadd_ps(p, _mm512_mul_ps(r, r), r), c(1.0));
    // y * 2^k, k in [-126, 127] after the clamp.
    _mm512_scalef_ps(y, k)
}

/// The exact (erf) GELU, `x/2 (1 + erf(x / sqrt 2))`, with erf by Abramowitz
/// & Stegun 7.1.26 (absolute error below 1.5e-7), branch-free.
#[inline(always)]
pub(crate) fn gelu_erf(x: f32) -> f32 {
    let z = x.abs() * std::f32::consts::FRAC_1_SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let poly = t
        * (0.254_829_6
            + t * (-0.284_496_74 + t * (1.421_413_8 + t * (-1.453_152 + t * 1.061_405_4))));
    let erf = (1.0 - poly * exp(-z * z)).copysign(x);
    0.5 * x * (1.0 + erf)
}

/// Largest absolute difference of two tensors of one shape (for tests).
#[cfg(test)]
pub(crate) fn max_abs_diff(a: &Tensor, b: &Tensor) -> f32 {
    (a - b)
        .and_then(|d| d.abs())
        .and_then(|d| d.max_all())
        .and_then(|d| d.to_dtype(DType::F32))
        .and_then(|d| d.to_scalar::<f32>())
        .expect("tensors of one shape")
}

/// `x * sigmoid(x)`.
#[inline(always)]
pub(crate) fn silu(x: f32) -> f32 {
    x / (1.0 + exp(-x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_is_accurate_over_softmax_range() {
        let mut worst = 0f64;
        for i in 0..200_000 {
            let x = -87.0 + i as f32 * (87.0 + 10.0) / 200_000.0;
            let want = f64::from(x).exp();
            let got = f64::from(exp(x));
            worst = worst.max(((got - want) / want).abs());
        }
        assert!(worst < 1e-6, "worst relative error {worst:e}");
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx512f") {
            use std::arch::x86_64::*;
            let xs: [f32; 16] = std::array::from_fn(|i| -87.0 + i as f32 * 11.5);
            let mut out = [0f32; 16];
            // SAFETY: AVX-512F was detected.
            unsafe { _mm512_storeu_ps(out.as_mut_ptr(), exp_avx512(_mm512_loadu_ps(xs.as_ptr()))) };
            for (x, y) in xs.iter().zip(out) {
                let want = f64::from(*x).exp();
                assert!(
                    ((f64::from(y) - want) / want).abs() < 1e-6,
                    "exp({x}) = {y}"
                );
            }
        }
        // candle's f64 GELU (erf to double precision) is the reference.
        let xs: Vec<f64> = (-4000..=4000).map(|i| f64::from(i) / 500.0).collect();
        let want = Tensor::new(xs.as_slice(), &Device::Cpu)
            .and_then(|t| t.gelu_erf())
            .and_then(|t| t.to_vec1::<f64>())
            .unwrap();
        for (x, want) in xs.iter().zip(want) {
            let got = f64::from(gelu_erf(*x as f32));
            assert!(
                (got - want).abs() < 1e-6 * (1.0 + x.abs()),
                "gelu({x}) = {got}, want {want}"
            );
        }
        assert!(exp(-1e9) >= 0.0 && exp(-1e9) < 1e-37);
        assert!(
            (silu(-100.0)).abs() < 1e-30 && (silu(3.0) - 3.0 / (1.0 + (-3f32).exp())).abs() < 1e-6
        );
    }

    #[test]
    fn matmul_handles_strided_views_and_accumulates() {
        // lhs 2x3 stored transposed, rhs 3x2 row-major.
        let lhs_t = [1f32, 4.0, 2.0, 5.0, 3.0, 6.0];
        let rhs = [1f32, 0.0, 0.0, 1.0, 1.0, 1.0];
        let mut dst = [10f32, 0.0, 0.0, 0.0];
        unsafe {
            matmul(
                (2, 2, 3),
                dst.as_mut_ptr(),
                2,
                true,
                View {
                    ptr: lhs_t.as_ptr(),
                    rs: 1,
                    cs: 2,
                },
                View {
                    ptr: rhs.as_ptr(),
                    rs: 2,
                    cs: 1,
                },
                true,
            )
        };
        assert_eq!(dst, [14.0, 5.0, 10.0, 11.0]);
    }
}
