//! Activations applied in place, fused into the kernel that produced the
//! values (one pass while they are still in cache).

use crate::model::Activation;

/// Applies `act` to `v` in place.
#[inline(always)]
pub(crate) fn apply(act: Activation, v: &mut [f32]) {
    match act {
        Activation::None => {}
        Activation::Relu => v.iter_mut().for_each(|x| *x = x.max(0.0)),
        Activation::Relu6 => v.iter_mut().for_each(|x| *x = x.clamp(0.0, 6.0)),
        Activation::ReluN1To1 => v.iter_mut().for_each(|x| *x = x.clamp(-1.0, 1.0)),
        Activation::Tanh => v.iter_mut().for_each(|x| *x = x.tanh()),
    }
}

/// Adds `bias` (one value per channel, channels innermost) to every pixel of
/// `v`, then applies `act`; in the CPU's widest vectors (the baseline x86-64
/// build has 4-wide SSE only: this pass was 7 % of a BlazePose frame).
pub(crate) fn bias_act(v: &mut [f32], bias: &[f32], act: Activation) {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has the feature the function is compiled for.
            return unsafe { bias_act_avx512(v, bias, act) };
        }
        if is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { bias_act_avx2(v, bias, act) };
        }
    }
    bias_act_plain(v, bias, act)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn bias_act_avx512(v: &mut [f32], bias: &[f32], act: Activation) {
    bias_act_plain(v, bias, act)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn bias_act_avx2(v: &mut [f32], bias: &[f32], act: Activation) {
    bias_act_plain(v, bias, act)
}

#[inline(always)]
fn bias_act_plain(v: &mut [f32], bias: &[f32], act: Activation) {
    for px in v.chunks_exact_mut(bias.len()) {
        for (x, b) in px.iter_mut().zip(bias) {
            *x += b;
        }
        apply(act, px);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn activations_and_bias() {
        let mut v = vec![-7.0, -0.5, 0.5, 7.0];
        apply(Activation::Relu6, &mut v);
        assert_eq!(v, [0.0, 0.0, 0.5, 6.0]);
        let mut v = vec![-7.0, -0.5, 0.5, 7.0];
        apply(Activation::ReluN1To1, &mut v);
        assert_eq!(v, [-1.0, -0.5, 0.5, 1.0]);
        let mut v = vec![1.0, -3.0, 2.0, -1.0];
        bias_act(&mut v, &[1.0, 2.0], Activation::Relu);
        assert_eq!(v, [2.0, 0.0, 3.0, 1.0]);
    }
}
