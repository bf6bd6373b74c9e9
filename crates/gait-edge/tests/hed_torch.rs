//! HED against controlnet_aux's torch implementation with seeded sparse random
//! weights (fixtures from `tools/edge/make_hed_fixtures.py`), on candle (.pth
//! and .safetensors) and ort (ONNX export of the same model).
//!
//! The ort tests need `ORT_DYLIB_PATH` (libonnxruntime.so) and fail without it.

use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use candle_core::{Device, Tensor};
use gait_core::{Backend, EdgeDetector, Frame, StageContext, StageError};
use gait_edge::{EdgeConfig, HedConfig, HedError, HedNetwork, SideOutput};
use image::RgbImage;
use tempfile::TempDir;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/hed")
        .join(name)
}

/// Un-gzips `NAME.gz` into `dir/NAME`.
fn unpack(dir: &TempDir, name: &str) -> PathBuf {
    let file = std::fs::File::open(fixture(&format!("{name}.gz"))).expect(name);
    let mut bytes = Vec::new();
    flate2::read::GzDecoder::new(file)
        .read_to_end(&mut bytes)
        .expect(name);
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect(name);
    path
}

fn input() -> RgbImage {
    image::open(fixture("input.png")).unwrap().to_rgb8()
}

fn expected() -> Vec<Tensor> {
    let t = candle_core::safetensors::load(fixture("expected.safetensors"), &Device::Cpu).unwrap();
    (1..=5).map(|i| t[&format!("side{i}")].clone()).collect()
}

fn require_ort() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some(),
        "ORT_DYLIB_PATH must point at libonnxruntime.so (e.g. /work/deps/onnxruntime/libonnxruntime.so.1.31.1) for the ort tests"
    );
}

/// Largest |ours - reference| over the largest |reference|, per side output.
fn relative_errors(ours: &[SideOutput], reference: &[(usize, usize, Vec<f32>)]) -> Vec<f64> {
    assert_eq!(ours.len(), 5);
    ours.iter()
        .zip(reference)
        .map(|(o, (w, h, r))| {
            assert_eq!((o.width, o.height), (*w, *h));
            let scale = r.iter().fold(0f32, |m, v| m.max(v.abs())) as f64;
            let diff = o
                .data
                .iter()
                .zip(r)
                .fold(0f32, |m, (a, b)| m.max((a - b).abs())) as f64;
            diff / scale
        })
        .collect()
}

fn torch_sides() -> Vec<(usize, usize, Vec<f32>)> {
    expected()
        .iter()
        .map(|t| {
            let (_, _, h, w) = t.dims4().unwrap();
            (w, h, t.flatten_all().unwrap().to_vec1::<f32>().unwrap())
        })
        .collect()
}

fn as_reference(sides: &[SideOutput]) -> Vec<(usize, usize, Vec<f32>)> {
    sides
        .iter()
        .map(|s| (s.width, s.height, s.data.clone()))
        .collect()
}

fn check_against_torch(label: &str, backend: Backend, path: &Path) -> Vec<SideOutput> {
    let mut net = HedNetwork::load(backend, path).unwrap();
    let sides = net.side_outputs(&input()).unwrap();
    let errors = relative_errors(&sides, &torch_sides());
    println!("{label}: relative errors vs torch {errors:?}");
    assert!(errors.iter().all(|&e| e <= 1e-4), "{label}: {errors:?}");
    sides
}

#[test]
fn candle_pth_side_outputs_match_torch() {
    let dir = TempDir::new().unwrap();
    check_against_torch(
        "candle .pth",
        Backend::Candle,
        &unpack(&dir, "hed_random.pth"),
    );
}

#[test]
fn candle_safetensors_side_outputs_match_torch() {
    let dir = TempDir::new().unwrap();
    check_against_torch(
        "candle .safetensors",
        Backend::Candle,
        &unpack(&dir, "hed_random.safetensors"),
    );
}

#[test]
fn ort_side_outputs_match_torch_and_candle() {
    require_ort();
    let dir = TempDir::new().unwrap();
    let ort = check_against_torch("ort", Backend::Ort, &unpack(&dir, "hed_random.onnx"));
    let mut candle = HedNetwork::load(Backend::Candle, &unpack(&dir, "hed_random.pth")).unwrap();
    let candle = candle.side_outputs(&input()).unwrap();
    let errors = relative_errors(&ort, &as_reference(&candle));
    println!("ort vs candle: relative errors {errors:?}");
    assert!(errors.iter().all(|&e| e <= 1e-4), "{errors:?}");
}

fn annotator_check(backend: Backend, weights: PathBuf, safe: bool, name: &str) {
    let config = HedConfig {
        backend,
        weights: Some(weights),
        safe,
        resolution: 64,
        ..HedConfig::default()
    };
    let mut detector = config.build(&StageContext::new("/nonexistent")).unwrap();
    let maps = detector.detect(&[Frame::new(3, input())]).unwrap();
    let ours = &maps[0].image;
    let reference = image::open(fixture(name)).unwrap().to_luma8();
    assert_eq!(ours.dimensions(), reference.dimensions());
    let diffs: Vec<u8> = ours
        .as_raw()
        .iter()
        .zip(reference.as_raw())
        .map(|(a, b)| a.abs_diff(*b))
        .collect();
    let max = diffs.iter().copied().max().unwrap();
    let off = diffs.iter().filter(|&&d| d > 0).count();
    println!(
        "{backend} {name}: max abs difference {max}, {off} of {} pixels differ",
        diffs.len()
    );
    // Float rounding can flip a truncation to uint8 (or a safe-step level) at a few pixels.
    assert!(
        max <= 1 || (safe && off <= 2),
        "max {max}, {off} pixels differ"
    );
    assert!(off * 100 <= diffs.len(), "{off} pixels differ");
}

#[test]
fn annotator_output_matches_controlnet_aux() {
    let dir = TempDir::new().unwrap();
    let pth = unpack(&dir, "hed_random.pth");
    annotator_check(Backend::Candle, pth.clone(), false, "annotator.png");
    annotator_check(Backend::Candle, pth, true, "annotator_safe.png");
}

#[test]
fn ort_annotator_output_matches_controlnet_aux() {
    require_ort();
    let dir = TempDir::new().unwrap();
    let onnx = unpack(&dir, "hed_random.onnx");
    annotator_check(Backend::Ort, onnx.clone(), false, "annotator.png");
    annotator_check(Backend::Ort, onnx, true, "annotator_safe.png");
}

#[test]
fn missing_weights_name_the_path_and_the_fetch_command() {
    let config: EdgeConfig = toml::from_str("kind = \"hed\"").unwrap();
    let ctx = StageContext::new("/no/such/models");
    assert_eq!(
        config.model_files(&ctx),
        vec![PathBuf::from("/no/such/models/ControlNetHED.pth")]
    );
    let err = config.build(&ctx).err().expect("must fail");
    assert!(matches!(err, StageError::MissingModel { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("/no/such/models/ControlNetHED.pth") && msg.contains("gait models fetch hed"),
        "{msg}"
    );
    let config: EdgeConfig = toml::from_str("kind = \"hed\"\nbackend = \"ort\"").unwrap();
    let msg = config.build(&ctx).err().expect("must fail").to_string();
    assert!(
        msg.contains("ControlNetHED.onnx") && msg.contains("gait models fetch hed"),
        "{msg}"
    );
}

fn write_modified(dir: &TempDir, edit: impl FnOnce(&mut HashMap<String, Tensor>)) -> PathBuf {
    let source = unpack(dir, "hed_random.safetensors");
    let mut tensors = candle_core::safetensors::load(&source, &Device::Cpu).unwrap();
    edit(&mut tensors);
    let path = dir.path().join("edited.safetensors");
    candle_core::safetensors::save(&tensors, &path).unwrap();
    path
}

#[test]
fn missing_tensor_is_named_with_its_shape() {
    let dir = TempDir::new().unwrap();
    let path = write_modified(&dir, |t| {
        t.remove("block3.convs.2.weight");
    });
    let err = HedNetwork::load(Backend::Candle, &path)
        .err()
        .expect("must fail");
    assert!(matches!(err, HedError::MissingTensor { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("block3.convs.2.weight") && msg.contains("[256, 256, 3, 3]"),
        "{msg}"
    );
}

#[test]
fn wrong_shape_is_named_with_expected_and_found() {
    let dir = TempDir::new().unwrap();
    let path = write_modified(&dir, |t| {
        t.insert(
            "block2.projection.weight".into(),
            Tensor::zeros((1, 64, 1, 1), candle_core::DType::F32, &Device::Cpu).unwrap(),
        );
    });
    let config = HedConfig {
        weights: Some(path.clone()),
        ..HedConfig::default()
    };
    let err = config
        .build(&StageContext::new("/nonexistent"))
        .err()
        .expect("must fail");
    let msg = err.to_string();
    assert!(matches!(err, StageError::BadModel { .. }), "{msg}");
    assert!(
        msg.contains("block2.projection.weight")
            && msg.contains("[1, 128, 1, 1]")
            && msg.contains("[1, 64, 1, 1]"),
        "{msg}"
    );
}

#[test]
fn garbage_file_is_a_bad_model() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("ControlNetHED.pth");
    std::fs::write(&path, b"not a checkpoint").unwrap();
    let config = HedConfig {
        weights: Some(path),
        ..HedConfig::default()
    };
    let err = config
        .build(&StageContext::new("/nonexistent"))
        .err()
        .expect("must fail");
    assert!(matches!(err, StageError::BadModel { .. }), "{err}");
}
