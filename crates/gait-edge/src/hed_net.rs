//! The layout of controlnet_aux's `ControlNetHED_Apache2`: a learned RGB
//! offset `norm`, then five VGG-style blocks of 3x3 convolutions + ReLU (2x2
//! max pooling before blocks 2..5), each with a 1x1 `projection` to one
//! channel, the block's side output.

/// (input channels, output channels, number of 3x3 convolutions) per block.
pub(crate) const BLOCKS: [(usize, usize, usize); 5] = [
    (3, 64, 2),
    (64, 128, 2),
    (128, 256, 3),
    (256, 512, 3),
    (512, 512, 3),
];

/// Name of the RGB offset subtracted from the 0..255 input.
pub(crate) const NORM: &str = "norm";

/// Every tensor of the checkpoint (`ControlNetHED.pth`) with its shape.
pub(crate) fn tensor_specs() -> Vec<(String, Vec<usize>)> {
    let mut specs = vec![(NORM.to_string(), vec![1, 3, 1, 1])];
    for (b, &(cin, cout, layers)) in BLOCKS.iter().enumerate() {
        for l in 0..layers {
            let inp = if l == 0 { cin } else { cout };
            let name = conv_name(b, l);
            specs.push((format!("{name}.weight"), vec![cout, inp, 3, 3]));
            specs.push((format!("{name}.bias"), vec![cout]));
        }
        let name = projection_name(b);
        specs.push((format!("{name}.weight"), vec![1, cout, 1, 1]));
        specs.push((format!("{name}.bias"), vec![1]));
    }
    specs
}

pub(crate) fn conv_name(block: usize, layer: usize) -> String {
    format!("block{}.convs.{layer}", block + 1)
}

pub(crate) fn projection_name(block: usize) -> String {
    format!("block{}.projection", block + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_count_matches_the_checkpoint() {
        let n: usize = tensor_specs()
            .iter()
            .map(|(_, s)| s.iter().product::<usize>())
            .sum();
        // torch: sum(p.numel() for p in ControlNetHED_Apache2().state_dict().values())
        assert_eq!(n, 14_716_168);
        assert_eq!(tensor_specs().len(), 1 + 2 * 13 + 2 * 5);
    }
}
