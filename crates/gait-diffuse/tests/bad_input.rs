//! Wrong checkpoints and edge maps of other sizes, on the tiny fixture models.

mod common;

use std::path::Path;

use gait_core::{EdgeMap, Frame, ImageRegenerator, Resize};
use gait_diffuse::{ControlnetConfig, ControlnetPipeline, ControlnetRegenerator, SchedulerKind};

fn edit_json(path: &Path, key: &str, value: serde_json::Value) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v[key] = value;
    std::fs::write(path, v.to_string()).unwrap();
}

fn load_err(sd: &Path, cn: &Path) -> String {
    match ControlnetPipeline::load(sd, cn, candle_core::DType::F32, &candle_core::Device::Cpu) {
        Ok(_) => panic!("loaded a wrong checkpoint"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn wrong_unet_checkpoint_names_file_and_tensor() {
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&common::tiny(), dir.path());
    // An SD 2.x-like UNet config against these weights: the text width differs.
    edit_json(
        &dir.path().join("unet/config.json"),
        "cross_attention_dim",
        16.into(),
    );
    edit_json(
        &dir.path().join("controlnet/config.json"),
        "cross_attention_dim",
        16.into(),
    );
    let msg = load_err(dir.path(), &dir.path().join("controlnet"));
    assert!(
        msg.contains("unet/diffusion_pytorch_model.safetensors"),
        "{msg}"
    );
    assert!(msg.contains("attn2.to_k.weight"), "{msg}");
}

#[test]
fn mismatched_controlnet_is_rejected_with_its_file() {
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&common::tiny(), dir.path());
    edit_json(
        &dir.path().join("controlnet/config.json"),
        "cross_attention_dim",
        16.into(),
    );
    let msg = load_err(dir.path(), &dir.path().join("controlnet"));
    assert!(
        msg.contains("controlnet/config.json") && msg.contains("cross-attention"),
        "{msg}"
    );
}

#[test]
fn unets_of_other_input_widths_are_rejected_with_their_config() {
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&common::tiny(), dir.path());
    edit_json(
        &dir.path().join("unet/config.json"),
        "in_channels",
        5.into(),
    );
    let msg = load_err(dir.path(), &dir.path().join("controlnet"));
    assert!(
        msg.contains("unet/config.json") && msg.contains("5 input channels"),
        "{msg}"
    );
}

#[test]
fn a_unet_file_given_as_controlnet_names_the_missing_tensor() {
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&common::tiny(), dir.path());
    std::fs::copy(
        dir.path().join("unet/diffusion_pytorch_model.safetensors"),
        dir.path()
            .join("controlnet/diffusion_pytorch_model.safetensors"),
    )
    .unwrap();
    let msg = load_err(dir.path(), &dir.path().join("controlnet"));
    assert!(
        msg.contains("controlnet/diffusion_pytorch_model.safetensors"),
        "{msg}"
    );
    assert!(msg.contains("controlnet_cond_embedding"), "{msg}");
}

fn regenerator(shared_noise: bool, batch: usize) -> ControlnetRegenerator {
    let cfg = ControlnetConfig {
        steps: 2,
        scheduler: SchedulerKind::Ddim,
        resolution: 64,
        batch,
        shared_noise,
        seed: 5,
        ..Default::default()
    };
    let pipe = ControlnetPipeline::load(
        &common::tiny(),
        &common::tiny().join("controlnet"),
        candle_core::DType::F32,
        &candle_core::Device::Cpu,
    )
    .unwrap();
    ControlnetRegenerator::from_pipeline(pipe, &cfg).unwrap()
}

fn max_diff(a: &Frame, b: &Frame) -> u8 {
    a.image
        .as_raw()
        .iter()
        .zip(b.image.as_raw())
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

fn inputs() -> (Vec<Frame>, Vec<EdgeMap>) {
    // 80x60 frames; edge maps at 40x30, the canvas (resolution 64) at 64x64.
    let frames: Vec<Frame> = (0..3)
        .map(|i| Frame::new(10 + i, image::RgbImage::new(80, 60)))
        .collect();
    let edges = frames
        .iter()
        .map(|f| {
            let img = image::GrayImage::from_fn(40, 30, |x, y| {
                image::Luma([if (x + y) % 7 == 0 { 255 } else { 0 }])
            });
            EdgeMap {
                index: f.index,
                image: img,
                resize: Resize::stretch(80, 60, 40, 30),
            }
        })
        .collect();
    (frames, edges)
}

#[test]
fn frames_keep_size_and_index_and_runs_are_reproducible() {
    let (frames, edges) = inputs();
    let mut r = regenerator(false, 2);
    let a = r.regenerate(&frames, Some(&edges)).unwrap();
    let b = r.regenerate(&frames, Some(&edges)).unwrap();
    assert_eq!(a, b, "same seeds give the same frames");
    for (f, o) in frames.iter().zip(&a) {
        assert_eq!((o.index, o.width(), o.height()), (f.index, 80, 60));
    }
    assert_ne!(a[0].image, a[1].image, "per-frame seeds differ");
    let single = regenerator(false, 1)
        .regenerate(&frames, Some(&edges))
        .unwrap();
    for (x, y) in a.iter().zip(&single) {
        let d = max_diff(x, y);
        assert!(d <= 1, "batched and single-frame runs agree (diff {d})");
    }
    let shared = regenerator(true, 1)
        .regenerate(&frames, Some(&edges))
        .unwrap();
    let d = max_diff(&shared[0], &shared[1]);
    assert!(
        d <= 1,
        "shared noise and equal edges give equal frames (diff {d})"
    );
    let Err(err) = r.regenerate(&frames, None) else {
        panic!("ran without edge maps")
    };
    assert!(err.to_string().contains("edge"), "{err}");
}
