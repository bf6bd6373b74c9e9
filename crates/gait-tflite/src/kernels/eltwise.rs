//! Element-wise kernels: ADD / MUL with the fused activation in the same
//! pass, and the standalone activations.

use candle_core::{Shape, bail};

use super::{Out, act};
use crate::model::Activation;

/// ADD or MUL.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Binary {
    Add,
    Mul,
}

/// Whether `binary` runs on these shapes: equal, or `b` one value per
/// channel of `a` (the last axis).
pub(crate) fn fits(a: &[usize], b: &[usize]) -> bool {
    a == b || (a.last().is_some() && b.iter().product::<usize>() == a[a.len() - 1])
}

/// `act(a op b)`, `b` equal in shape to `a` or broadcast along its last axis.
pub(crate) fn binary(
    op: Binary,
    act: Activation,
    a: &[f32],
    ad: &[usize],
    b: &[f32],
    bd: &[usize],
) -> Out {
    if !fits(ad, bd) || b.is_empty() {
        bail!("{op:?}: cannot broadcast {bd:?} to {ad:?}")
    }
    let mut out = Vec::with_capacity(a.len());
    for chunk in a.chunks(b.len()) {
        let start = out.len();
        match op {
            Binary::Add => out.extend(chunk.iter().zip(b).map(|(x, y)| x + y)),
            Binary::Mul => out.extend(chunk.iter().zip(b).map(|(x, y)| x * y)),
        }
        act::apply(act, &mut out[start..]);
    }
    Ok((out, Shape::from(ad)))
}

/// A standalone activation operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unary {
    HardSwish,
    Logistic,
    Relu,
    Relu6,
}

/// `op` applied to every element.
pub(crate) fn unary(op: Unary, x: &[f32], dims: &[usize]) -> Out {
    let f: fn(f32) -> f32 = match op {
        // x * relu6(x + 3) / 6
        Unary::HardSwish => |v| v * (v + 3.0).clamp(0.0, 6.0) * (1.0 / 6.0),
        Unary::Logistic => |v| 1.0 / (1.0 + (-v).exp()),
        Unary::Relu => |v| v.max(0.0),
        Unary::Relu6 => |v| v.clamp(0.0, 6.0),
    };
    Ok((x.iter().map(|&v| f(v)).collect(), Shape::from(dims)))
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::kernels::testutil::{max_diff, tensor};

    fn run(op: Binary, act: Activation, a: &Tensor, b: &Tensor) -> Tensor {
        let av = a.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let bv = b.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let (v, s) = binary(op, act, &av, a.dims(), &bv, b.dims()).unwrap();
        Tensor::from_vec(v, s, &Device::Cpu).unwrap()
    }

    #[test]
    fn binary_matches_candle() {
        let a = tensor(&[1, 3, 4, 5], 7);
        let b = tensor(&[1, 3, 4, 5], 8);
        let c = tensor(&[1, 1, 1, 5], 9);
        let want = (&a + &b).unwrap().relu().unwrap();
        assert!(max_diff(&run(Binary::Add, Activation::Relu, &a, &b), &want) < 1e-6);
        let want = a.broadcast_mul(&c).unwrap();
        assert!(max_diff(&run(Binary::Mul, Activation::None, &a, &c), &want) < 1e-6);
        assert!(!fits(&[1, 3, 4, 5], &[1, 3, 1, 1]));
    }

    #[test]
    fn unary_matches_candle() {
        let x = (tensor(&[2, 50], 10) * 8.0).unwrap();
        let xv = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let ours = |op| {
            let (v, s) = unary(op, &xv, x.dims()).unwrap();
            Tensor::from_vec(v, s, &Device::Cpu).unwrap()
        };
        let hs = x
            .affine(1.0, 3.0)
            .and_then(|t| t.clamp(0f32, 6f32))
            .and_then(|t| t.mul(&x))
            .and_then(|t| t.affine(1.0 / 6.0, 0.0))
            .unwrap();
        assert!(max_diff(&ours(Unary::HardSwish), &hs) < 1e-5);
        let sig = candle_core::Tensor::ones_like(&x)
            .and_then(|one| one.broadcast_div(&(x.neg().unwrap().exp().unwrap() + 1.0).unwrap()))
            .unwrap();
        assert!(max_diff(&ours(Unary::Logistic), &sig) < 1e-6);
        assert!(max_diff(&ours(Unary::Relu), &x.relu().unwrap()) < 1e-7);
        assert!(max_diff(&ours(Unary::Relu6), &x.clamp(0f32, 6f32).unwrap()) < 1e-7);
    }
}
