//! Our loaders ask for exactly the tensors of the real SD 1.5 and
//! sd-controlnet-canny checkpoints (manifest from diffusers' configs by
//! tools/diffuse/make_manifest.py): none missing, none extra, same shapes.

mod common;

use std::collections::BTreeMap;

use gait_diffuse::model_config::{TextConfig, UnetConfig, VaeConfig};
use gait_diffuse::weights::{Component, requested_tensors};

#[test]
fn loaders_request_exactly_the_real_checkpoints_tensors() {
    let text = std::fs::read_to_string(common::fixtures().join("sd15_manifest.json")).unwrap();
    let manifest: BTreeMap<String, BTreeMap<String, Vec<usize>>> =
        serde_json::from_str(&text).unwrap();
    // The VAE file holds the decoder (every run) and the encoder (image-to-image, inpainting).
    for (key, components) in [
        ("unet", &[Component::Unet][..]),
        ("controlnet", &[Component::ControlNet]),
        ("vae", &[Component::Vae, Component::VaeEncoder]),
        ("text_encoder", &[Component::TextEncoder]),
    ] {
        let want = &manifest[key];
        let mut got = BTreeMap::new();
        for &component in components {
            got.extend(
                requested_tensors(
                    component,
                    &UnetConfig::default(),
                    &VaeConfig::default(),
                    &TextConfig::default(),
                    want.keys().cloned().collect(),
                )
                .unwrap(),
            );
        }
        let missing: Vec<_> = want.keys().filter(|k| !got.contains_key(*k)).collect();
        let extra: Vec<_> = got.keys().filter(|k| !want.contains_key(*k)).collect();
        assert!(
            missing.is_empty(),
            "{key}: loader never asks for {missing:?}"
        );
        assert!(
            extra.is_empty(),
            "{key}: loader asks for tensors not in the checkpoint {extra:?}"
        );
        for (name, shape) in want {
            // Linear weights stored as 1x1 convolutions (VAE attention) are reshaped on load.
            let ours = &got[name];
            let same =
                ours == shape || ours.iter().product::<usize>() == shape.iter().product::<usize>();
            assert!(
                same,
                "{key}: {name} requested as {ours:?}, checkpoint has {shape:?}"
            );
        }
        println!("{key}: {} tensors match", want.len());
    }
}
