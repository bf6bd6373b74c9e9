//! The OpenPose networks against the reference: controlnet_aux's torch model
//! (COCO-18) and a torch module of the BODY_25 caffe architecture, both with
//! the synthetic weights of tools/openpose/synthetic_weights.py, on a real
//! frame. Fixtures: tools/openpose/make_net_fixtures.py.
//!
//! Error measure: max |ours - torch| over all elements of an output, divided
//! by max |torch| of that output (heatmaps and PAFs separately), <= 1e-4.

#[path = "openpose_net/synthetic.rs"]
mod synthetic;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use candle_core::{Device, Tensor};
use gait_core::Backend;
use gait_pose::openpose::net::{self, OrtNet, WeightsError};
use gait_pose::openpose::{NetInput, NetOutput, OpenposeModel, OpenposeNet};
use serde_json::Value;

const TOLERANCE: f32 = 1e-4;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/openpose/net")
}

fn json(name: &str) -> Value {
    let text = std::fs::read_to_string(dir().join(name)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn floats(name: &str) -> Vec<f32> {
    std::fs::read(dir().join(name))
        .unwrap()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// (checkpoint name, torch name, shape) of every tensor, in formula order.
fn manifest(file: &str) -> Vec<(String, String, Vec<usize>)> {
    json(file)
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let shape = e["shape"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d.as_u64().unwrap() as usize);
            (
                e["name"].as_str().unwrap().to_string(),
                e["torch"].as_str().unwrap().to_string(),
                shape.collect(),
            )
        })
        .collect()
}

/// The test image as body.py feeds it: BGR bytes / 256 - 0.5, CHW.
fn input() -> NetInput {
    let cases = json("cases.json");
    let (h, w) = (
        cases["input"]["height"].as_u64().unwrap() as usize,
        cases["input"]["width"].as_u64().unwrap() as usize,
    );
    let bgr = std::fs::read(dir().join("input_bgr.bin")).unwrap();
    assert_eq!(bgr.len(), h * w * 3);
    let mut data = vec![0f32; 3 * h * w];
    for (p, px) in bgr.chunks_exact(3).enumerate() {
        for c in 0..3 {
            data[c * h * w + p] = px[c] as f32 / 256.0 - 0.5;
        }
    }
    NetInput {
        data,
        height: h,
        width: w,
    }
}

fn rel_err(ours: &[f32], reference: &[f32]) -> f32 {
    assert_eq!(ours.len(), reference.len());
    let max_ref = reference.iter().fold(0f32, |m, v| m.max(v.abs()));
    assert!(max_ref > 0.0, "reference output is all zeros");
    let max_diff = ours
        .iter()
        .zip(reference)
        .fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    max_diff / max_ref
}

/// Compares a network output with the torch fixture of `case`.
fn check(out: &NetOutput, case: &str) {
    let c = &json("cases.json")[case];
    let (nh, np) = (
        c["heatmap_channels"].as_u64().unwrap() as usize,
        c["paf_channels"].as_u64().unwrap() as usize,
    );
    let (h, w) = (
        c["height"].as_u64().unwrap() as usize,
        c["width"].as_u64().unwrap() as usize,
    );
    assert_eq!((out.height, out.width), (h, w));
    let reference = floats(c["output"].as_str().unwrap());
    let (heat, paf) = reference.split_at(nh * h * w);
    assert_eq!(paf.len(), np * h * w);
    let (eh, ep) = (rel_err(&out.heatmaps, heat), rel_err(&out.pafs, paf));
    println!("{case}: heatmaps max rel err {eh:.2e}, PAFs {ep:.2e}");
    assert!(
        eh <= TOLERANCE && ep <= TOLERANCE,
        "{case}: heatmaps {eh:.2e}, PAFs {ep:.2e}"
    );
}

fn coco18_tensors() -> HashMap<String, Tensor> {
    manifest("coco18_manifest.json")
        .into_iter()
        .enumerate()
        .map(|(k, (name, torch, shape))| {
            let n = shape.iter().product();
            let v = synthetic::values(k, n, synthetic::scale(&torch, &shape));
            (name, Tensor::from_vec(v, shape, &Device::Cpu).unwrap())
        })
        .collect()
}

/// Zero tensors of the layout without allocating them (broadcast views).
fn coco18_cheap() -> HashMap<String, Tensor> {
    let zero = Tensor::zeros(1, candle_core::DType::F32, &Device::Cpu).unwrap();
    manifest("coco18_manifest.json")
        .into_iter()
        .map(|(name, _, shape)| {
            let t = zero
                .reshape(vec![1; shape.len()])
                .unwrap()
                .broadcast_as(shape)
                .unwrap();
            (name, t)
        })
        .collect()
}

#[test]
fn loader_asks_for_exactly_the_checkpoint_layout() {
    let layout = net::coco18_layout();
    let manifest: Vec<(String, Vec<usize>)> = manifest("coco18_manifest.json")
        .into_iter()
        .map(|(n, _, s)| (n, s))
        .collect();
    assert_eq!(layout, manifest);
    assert!(net::candle_from_tensors(coco18_cheap()).is_ok());
}

#[test]
fn loader_names_missing_misshaped_and_unknown_tensors() {
    for name in [
        "conv1_1.weight",
        "conv4_4_CPM.bias",
        "Mconv7_stage6_L2.weight",
    ] {
        let mut t = coco18_cheap();
        t.remove(name);
        let e = net::candle_from_tensors(t).err().unwrap();
        assert!(matches!(&e, WeightsError::Missing(n) if n == name), "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
    let mut t = coco18_cheap();
    t.insert(
        "Mconv3_stage4_L1.weight".into(),
        Tensor::zeros((128, 128, 3, 3), candle_core::DType::F32, &Device::Cpu).unwrap(),
    );
    let e = net::candle_from_tensors(t).err().unwrap().to_string();
    assert!(
        e.contains("Mconv3_stage4_L1.weight") && e.contains("[128, 128, 7, 7]"),
        "{e}"
    );
    let mut t = coco18_cheap();
    t.insert(
        "conv5_1.weight".into(),
        Tensor::zeros(3, candle_core::DType::F32, &Device::Cpu).unwrap(),
    );
    let e = net::candle_from_tensors(t).err().unwrap().to_string();
    assert!(e.contains("conv5_1.weight"), "{e}");
}

/// The tiny checkpoints hold a few tensors of the real layout, written by
/// torch.save in both formats; their values are the synthetic formula's.
#[test]
fn pth_reader_reads_torch_zip_and_legacy_files() {
    let manifest = manifest("coco18_manifest.json");
    let picks = json("cases.json")["tiny_pth"].as_array().unwrap().clone();
    for file in ["tiny_zip.pth", "tiny_legacy.pth"] {
        let tensors = net::read_checkpoint(&dir().join(file)).unwrap();
        assert_eq!(tensors.len(), picks.len(), "{file}");
        for p in &picks {
            let (name, k) = (
                p["name"].as_str().unwrap(),
                p["tensor"].as_u64().unwrap() as usize,
            );
            let (mname, torch, shape) = &manifest[k];
            assert_eq!(mname, name);
            let t = &tensors[name];
            assert_eq!(t.dims(), shape.as_slice(), "{file} {name}");
            let got = t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            let want = synthetic::values(k, got.len(), synthetic::scale(torch, shape));
            assert_eq!(got, want, "{file} {name}");
        }
        // Loading it as the model fails on the first tensor it lacks, naming it and the file.
        let e = net::load(&dir().join(file), OpenposeModel::Coco18, Backend::Candle)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("conv1_2.weight") && e.contains(file), "{e}");
    }
}

#[test]
fn safetensors_with_the_same_names_load() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("body.safetensors");
    let mut t = coco18_tensors();
    candle_core::safetensors::save(&t, &path).unwrap();
    let mut model = net::load(&path, OpenposeModel::Coco18, Backend::Candle).unwrap();
    check(&model.run(&input()).unwrap(), "coco18");
    t.remove("conv3_2.bias");
    candle_core::safetensors::save(&t, &path).unwrap();
    let e = net::load(&path, OpenposeModel::Coco18, Backend::Candle)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("conv3_2.bias") && e.contains("body.safetensors"),
        "{e}"
    );
}

#[test]
fn candle_coco18_matches_controlnet_aux() {
    let mut model = net::candle_from_tensors(coco18_tensors()).unwrap();
    assert_eq!(model.model(), OpenposeModel::Coco18);
    check(&model.run(&input()).unwrap(), "coco18");
    let bad = NetInput {
        data: vec![0.0; 3 * 12 * 16],
        height: 12,
        width: 16,
    };
    assert!(model.run(&bad).is_err());
}

#[test]
fn candle_refuses_body25() {
    let e = net::load(
        &dir().join("tiny_zip.pth"),
        OpenposeModel::Body25,
        Backend::Candle,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("ort") && e.contains("ONNX"), "{e}");
}

fn require_ort() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some(),
        "ORT_DYLIB_PATH is not set: point it at libonnxruntime.so (tools/setup.sh fetches it) to run the ort tests"
    );
}

/// Copies `name`.onnx into a temp dir and writes its external weights there
/// from the formula, as the sidecar says.
fn rebuild_onnx(name: &str, manifest_file: &str) -> (tempfile::TempDir, PathBuf) {
    let manifest = manifest(manifest_file);
    let side = json(&format!("{name}.onnx.weights.json"));
    let mut blob = vec![0u8; side["file_length"].as_u64().unwrap() as usize];
    for e in side["initializers"].as_array().unwrap() {
        let k = e["tensor"].as_u64().unwrap() as usize;
        let (off, len) = (
            e["offset"].as_u64().unwrap() as usize,
            e["length"].as_u64().unwrap() as usize,
        );
        let (_, torch, shape) = &manifest[k];
        assert_eq!(len, 4 * shape.iter().product::<usize>(), "{}", e["name"]);
        let v = synthetic::values(k, len / 4, synthetic::scale(torch, shape));
        for (dst, x) in blob[off..off + len].chunks_exact_mut(4).zip(v) {
            dst.copy_from_slice(&x.to_le_bytes());
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join(side["location"].as_str().unwrap()), blob).unwrap();
    let onnx = tmp.path().join(format!("{name}.onnx"));
    std::fs::copy(dir().join(format!("{name}.onnx")), &onnx).unwrap();
    (tmp, onnx)
}

#[test]
fn ort_coco18_matches_controlnet_aux() {
    require_ort();
    let (_tmp, onnx) = rebuild_onnx("coco18", "coco18_manifest.json");
    let mut model = net::load(&onnx, OpenposeModel::Coco18, Backend::Ort).unwrap();
    check(&model.run(&input()).unwrap(), "coco18");
}

#[test]
fn ort_body25_caffe_style_output_matches_torch() {
    require_ort();
    let (_tmp, onnx) = rebuild_onnx("body25", "body25_manifest.json");
    let mut model = OrtNet::load(&onnx, OpenposeModel::Body25, gait_core::Device::Cpu).unwrap();
    assert_eq!(model.model(), OpenposeModel::Body25);
    check(&model.run(&input()).unwrap(), "body25");
    // The same file configured as COCO-18: 78 channels are not 19 + 38.
    let mut wrong = OrtNet::load(&onnx, OpenposeModel::Coco18, gait_core::Device::Cpu).unwrap();
    let e = wrong.run(&input()).err().unwrap().to_string();
    assert!(e.contains("78") && e.contains("57"), "{e}");
}
