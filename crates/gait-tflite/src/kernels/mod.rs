//! NHWC float kernels on contiguous slices, and the adapters that run them as
//! candle custom ops (the graph's values stay candle tensors).

pub(crate) mod act;
pub(crate) mod conv;
pub(crate) mod depthwise;
pub(crate) mod eltwise;
pub(crate) mod pad;
pub(crate) mod pool;
pub(crate) mod resize;
#[cfg(test)]
pub(crate) mod testutil;

use candle_core::{CpuStorage, CustomOp1, CustomOp2, Layout, Shape, Tensor, bail};

/// Output of a kernel: data and shape.
pub(crate) type Out = candle_core::Result<(Vec<f32>, Shape)>;

/// A kernel on one input's data and dims.
pub(crate) type Kernel1<'a> = dyn Fn(&[f32], &[usize]) -> Out + Send + Sync + 'a;

/// A kernel on two inputs' data and dims.
pub(crate) type Kernel2<'a> = dyn Fn(&[f32], &[usize], &[f32], &[usize]) -> Out + Send + Sync + 'a;

fn slice<'a>(
    storage: &'a CpuStorage,
    layout: &Layout,
    name: &str,
) -> candle_core::Result<&'a [f32]> {
    let CpuStorage::F32(data) = storage else {
        bail!("{name}: f32 input expected")
    };
    let Some((a, b)) = layout.contiguous_offsets() else {
        bail!("{name}: contiguous input expected")
    };
    Ok(&data[a..b])
}

/// A one-input kernel as a candle op.
struct Op1<'a> {
    name: &'static str,
    f: &'a Kernel1<'a>,
}

impl CustomOp1 for Op1<'_> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn cpu_fwd(&self, s: &CpuStorage, l: &Layout) -> candle_core::Result<(CpuStorage, Shape)> {
        let (v, shape) = (self.f)(slice(s, l, self.name)?, l.dims())?;
        Ok((CpuStorage::F32(v), shape))
    }
}

/// A two-input kernel as a candle op.
struct Op2<'a> {
    name: &'static str,
    f: &'a Kernel2<'a>,
}

impl CustomOp2 for Op2<'_> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let a = slice(s1, l1, self.name)?;
        let b = slice(s2, l2, self.name)?;
        let (v, shape) = (self.f)(a, l1.dims(), b, l2.dims())?;
        Ok((CpuStorage::F32(v), shape))
    }
}

/// Runs `f` on the contiguous f32 data of `x` (copied first if strided).
pub(crate) fn apply1(x: &Tensor, name: &'static str, f: &Kernel1) -> candle_core::Result<Tensor> {
    let x = x.contiguous()?;
    x.apply_op1_no_bwd(&Op1 { name, f })
}

/// Runs `f` on the contiguous f32 data of `a` and `b`.
pub(crate) fn apply2(
    a: &Tensor,
    b: &Tensor,
    name: &'static str,
    f: &Kernel2<'_>,
) -> candle_core::Result<Tensor> {
    let (a, b) = (a.contiguous()?, b.contiguous()?);
    a.apply_op2_no_bwd(&b, &Op2 { name, f })
}

/// `[1, h, w, c]` of an NHWC input, or an error naming the kernel.
pub(crate) fn nhwc(dims: &[usize], name: &str) -> candle_core::Result<(usize, usize, usize)> {
    match *dims {
        [1, h, w, c] => Ok((h, w, c)),
        _ => bail!("{name}: [1, h, w, c] input expected, got {dims:?}"),
    }
}
