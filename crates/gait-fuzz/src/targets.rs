//! One fuzz target per input parser: the bytes go where a user's file would (a file of the
//! right name, or the parser's byte entry) and whatever the parser accepts is used as the
//! program would use it next. An error is a pass; a panic, abort, huge allocation or hang is a
//! crash (see [`crate::engine`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use gait_core::PoseSequence;

/// A parser under test.
pub struct Target {
    pub name: &'static str,
    /// Seed files (relative to the repository), or folders whose files with `ext` are seeds.
    pub seeds: &'static [&'static str],
    pub ext: &'static str,
    pub run: fn(&Scratch, &[u8]),
}

/// A private folder for the files a target writes (on /dev/shm where there is one).
pub struct Scratch {
    dir: tempfile::TempDir,
}

impl Scratch {
    pub fn new() -> std::io::Result<Self> {
        let shm = Path::new("/dev/shm");
        let dir = if shm.is_dir() {
            tempfile::tempdir_in(shm)?
        } else {
            tempfile::tempdir()?
        };
        Ok(Scratch { dir })
    }

    /// Writes `bytes` as `name` in the scratch folder.
    pub fn file(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.dir.path().join(name);
        if let Some(parent) = p.parent() {
            let _ = std::fs::create_dir_all(parent);
        }
        let _ = std::fs::write(&p, bytes);
        p
    }

    pub fn path(&self) -> &Path {
        self.dir.path()
    }
}

/// The sample's subject-tracked keypoints (frames 59-192 are the walker), for the targets that
/// check their input against keypoints.
fn sample() -> &'static PoseSequence {
    static SEQ: OnceLock<PoseSequence> = OnceLock::new();
    SEQ.get_or_init(|| {
        let p = crate::repo().join("tests/data/sample-subject/keypoints.csv");
        let f = std::fs::File::open(p).expect("tests/data/sample-subject/keypoints.csv");
        gait_core::dlc::read(f, None, 30.0).expect("the sample keypoints parse")
    })
}

fn kin_config() -> gait_kin::KinematicsConfig {
    gait_kin::KinematicsConfig {
        frame_size: Some([1768, 994]),
        ..Default::default()
    }
}

fn dlc_csv(_: &Scratch, b: &[u8]) {
    if let Ok(seq) = gait_core::dlc::read(b, None, 30.0) {
        // Hostile numbers must get through the whole analysis too.
        let _ = gait_kin::analyse(&seq, &Default::default(), &kin_config());
    }
}

fn openpose_json(s: &Scratch, b: &[u8]) {
    let dir = s.path().join("openpose");
    let _ = std::fs::remove_dir_all(&dir);
    s.file("openpose/walk_000000000000_keypoints.json", b);
    s.file("openpose/walk_000000000001_keypoints.json", b);
    let _ = gait_eval::openpose::read_dir(&dir, 30.0);
}

fn pipeline_toml(s: &Scratch, b: &[u8]) {
    let _ = gait_pipeline::PipelineConfig::load(Some(&s.file("pipeline.toml", b)), &[]);
}

fn run_json(s: &Scratch, b: &[u8]) {
    let _ = gait_pipeline::PipelineConfig::load(Some(&s.file("run.json", b)), &[]);
}

fn corrections(s: &Scratch, b: &[u8]) {
    let path = s.file("corrections.toml", b);
    if let Ok(c) = gait_kin::Corrections::read(&path)
        && c.validate_file(sample(), &path).is_ok()
    {
        let _ = gait_kin::analyse_corrected(
            sample(),
            &Default::default(),
            &kin_config(),
            &c,
            &path,
            String::new(),
        );
    }
}

fn study_csv(s: &Scratch, b: &[u8]) {
    let _ = gait_batch::Study::read(&s.file("study.csv", b));
}

fn study_toml(s: &Scratch, b: &[u8]) {
    let _ = gait_batch::Study::read(&s.file("study.toml", b));
}

fn events_csv(s: &Scratch, b: &[u8]) {
    let _ = gait_kin::events::read_csv(&s.file("events.csv", b));
}

fn normative_csv(s: &Scratch, b: &[u8]) {
    let p = s.file("lab.csv", b);
    let _ = gait_eval::Normative::load(&p.display().to_string());
}

fn tflite(_: &Scratch, b: &[u8]) {
    let _ = gait_tflite::Graph::parse(b);
}

/// A parsed graph built as the pose stage builds it: compiled for candle and
/// converted to ONNX (declared shapes size the buffers of both).
fn tflite_graph(_: &Scratch, b: &[u8]) {
    if let Ok(g) = gait_tflite::Graph::parse(b) {
        let _ = gait_tflite::CandleGraph::new(&g);
        let _ = gait_tflite::to_onnx(&g);
    }
}

fn safetensors(_: &Scratch, b: &[u8]) {
    let _ = candle_core::safetensors::load_buffer(b, &candle_core::Device::Cpu);
}

/// OpenPose's and HED's `.pth` reader (`gait_core::checkpoint`, shared).
fn pth(s: &Scratch, b: &[u8]) {
    let _ = gait_pose::openpose::net::read_checkpoint(&s.file("model.pth", b));
}

/// An ONNX graph as the OpenPose ort backend opens it (ONNX Runtime parses it; we check its
/// inputs and outputs), then run on one 16x16 image whose outputs we check and decode.
fn onnx(s: &Scratch, b: &[u8]) {
    use gait_pose::openpose::{NetInput, OpenposeModel, OpenposeNet};
    let p = s.file("openpose.onnx", b);
    // COCO-18 exports of the PyTorch body model name their first layer `model0.conv1_1`.
    let coco = b.windows(14).any(|w| w == b"model0.conv1_1");
    let model = match coco {
        true => OpenposeModel::Coco18,
        false => OpenposeModel::Body25,
    };
    if let Ok(mut net) = gait_pose::openpose::net::OrtNet::load(&p, model, gait_core::Device::Cpu) {
        let input = NetInput {
            data: vec![0.5; 3 * 16 * 16],
            height: 16,
            width: 16,
        };
        let _ = net.run(&input);
    }
}

fn clip_merges(_: &Scratch, b: &[u8]) {
    if let Ok(t) = gait_diffuse::ClipTokenizer::from_merges(&String::from_utf8_lossy(b)) {
        let _ = t.encode("a person walking with intact legs, full body, photo");
    }
}

/// The tiny SD 1.5 + ControlNet fixture's folders, each with its `config.json`.
const TINY: &str = "crates/gait-diffuse/tests/fixtures/tiny";
const MODEL_SLOTS: [&str; 4] = ["unet", "controlnet", "vae", "text_encoder"];

/// Which model a `config.json` is for, by the class it names (the UNet's when none).
fn config_slot(b: &[u8]) -> usize {
    let has = |k: &[u8]| b.windows(k.len()).any(|w| w == k);
    [
        b"ControlNetModel".as_slice(),
        b"AutoencoderKL",
        b"clip_text_model",
    ]
    .iter()
    .position(|k| has(k))
    .map_or(0, |i| i + 1)
}

/// A diffusers `config.json`: it replaces the tiny model's config of the kind it names, the
/// four models are built from the configs and the real tiny weights, and a model that loads
/// runs one denoising step (a config can pass the weights' shape checks with hostile values).
fn diffusers_config(s: &Scratch, b: &[u8]) {
    use candle_core::{DType, Device, Tensor};
    let dir = s.path().join("sd");
    let tiny = crate::repo().join(TINY);
    let slot = config_slot(b);
    if !dir.join("tokenizer").exists() {
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::os::unix::fs::symlink(tiny.join("tokenizer"), dir.join("tokenizer"));
    }
    for (i, name) in MODEL_SLOTS.iter().enumerate() {
        let (from, to) = (tiny.join(name), dir.join(name));
        if !to.is_dir() {
            let _ = std::fs::create_dir_all(&to);
            for f in std::fs::read_dir(&from).into_iter().flatten().flatten() {
                let _ = std::os::unix::fs::symlink(f.path(), to.join(f.file_name()));
            }
        }
        let config = to.join("config.json");
        let _ = std::fs::remove_file(&config);
        let _ = match i == slot {
            true => std::fs::write(&config, b),
            false => std::fs::copy(from.join("config.json"), &config).map(|_| ()),
        };
    }
    let cpu = Device::Cpu;
    let Ok(pipe) =
        gait_diffuse::ControlnetPipeline::load(&dir, &dir.join("controlnet"), DType::F32, &cpu)
    else {
        return;
    };
    let scale = pipe.vae_scale();
    let (Ok(context), Ok(latents), Ok(control)) = (
        pipe.context("a person walking", "", 2.0),
        Tensor::zeros((1, 4, 2, 2), DType::F32, &cpu),
        Tensor::zeros((1, 3, 2 * scale, 2 * scale), DType::F32, &cpu),
    ) else {
        return;
    };
    let p = gait_diffuse::DenoiseParams {
        steps: 1,
        guidance_scale: 2.0,
        conditioning_scale: 1.0,
        scheduler: gait_diffuse::SchedulerKind::Ddim,
        cutoffs: Default::default(),
        savings: Default::default(),
    };
    let _ = pipe.generate(&context, &control, &latents, &p);
}

/// The file name a user's image would have, from its first bytes (the decoders are chosen by
/// extension, so a JPEG named `.png` would never reach the JPEG decoder).
fn image_name(b: &[u8]) -> &'static str {
    match b {
        [0xff, 0xd8, ..] => "frame.jpg",
        [b'B', b'M', ..] => "frame.bmp",
        [b'I', b'I', ..] | [b'M', b'M', ..] => "frame.tif",
        _ => "frame.png",
    }
}

fn image(s: &Scratch, b: &[u8]) {
    let p = s.file(image_name(b), b);
    if let Ok(info) = gait_pipeline::input::InputInfo::open(&p)
        && let Ok(mut frames) = info.frames()
    {
        let _ = frames.next_frame();
    }
}

fn ffprobe_json(s: &Scratch, b: &[u8]) {
    let _ = gait_pipeline::input::parse_ffprobe(&s.path().join("clip.mp4"), b);
}

fn video(s: &Scratch, b: &[u8]) {
    let p = s.file("clip.mp4", b);
    if let Ok(info) = gait_pipeline::input::InputInfo::open(&p)
        && let Ok(mut frames) = info.frames()
    {
        while let Ok(Some(_)) = frames.next_frame() {}
    }
}

/// The video reader on a recorded ffprobe and ffmpeg run ([`crate::recording`]): all that our
/// code does with a video, in-process; `video` runs the real tools on mutated video files.
fn video_stream(s: &Scratch, b: &[u8]) {
    let (probe, decoded) = crate::recording::unpack(b);
    if let Ok(info) = gait_pipeline::input::parse_ffprobe(&s.path().join("clip.mp4"), probe) {
        let mut frames = info.replay(decoded);
        while let Ok(Some(_)) = frames.next_frame() {}
    }
}

/// Every target, in the order the runner takes them.
pub const TARGETS: &[Target] = &[
    Target {
        name: "dlc_csv",
        seeds: &["fuzz/seeds/dlc_csv"],
        ext: "csv",
        run: dlc_csv,
    },
    Target {
        name: "openpose_json",
        seeds: &["crates/gait-eval/tests/fixtures/metrics/pred_openpose"],
        ext: "json",
        run: openpose_json,
    },
    Target {
        name: "pipeline_toml",
        seeds: &["configs"],
        ext: "toml",
        run: pipeline_toml,
    },
    Target {
        name: "run_json",
        seeds: &["fuzz/seeds/run_json"],
        ext: "json",
        run: run_json,
    },
    Target {
        name: "corrections",
        seeds: &["fuzz/seeds/corrections"],
        ext: "toml",
        run: corrections,
    },
    Target {
        name: "study_csv",
        seeds: &["fuzz/seeds/study"],
        ext: "csv",
        run: study_csv,
    },
    Target {
        name: "study_toml",
        seeds: &["fuzz/seeds/study"],
        ext: "toml",
        run: study_toml,
    },
    Target {
        name: "events_csv",
        seeds: &[
            "tests/data/sample-events/events.csv",
            "tests/data/fukuchi2018/events.csv",
        ],
        ext: "csv",
        run: events_csv,
    },
    Target {
        name: "normative_csv",
        seeds: &["crates/gait-eval/data/normative/schwartz2008_free.csv"],
        ext: "csv",
        run: normative_csv,
    },
    Target {
        name: "tflite",
        seeds: &["target/models/blazepose/selfie_segmentation.tflite"],
        ext: "tflite",
        run: tflite,
    },
    Target {
        name: "tflite_graph",
        seeds: &[
            "target/models/blazepose/selfie_segmentation.tflite",
            "target/models/blazepose/pose_detection.tflite",
        ],
        ext: "tflite",
        run: tflite_graph,
    },
    Target {
        name: "safetensors",
        seeds: &["crates/gait-edge/tests/fixtures/hed/expected.safetensors"],
        ext: "safetensors",
        run: safetensors,
    },
    Target {
        name: "pth",
        seeds: &["crates/gait-pose/tests/fixtures/openpose/net"],
        ext: "pth",
        run: pth,
    },
    Target {
        name: "onnx",
        seeds: &[
            "crates/gait-pose/tests/fixtures/openpose/net/coco18.onnx",
            "crates/gait-pose/tests/fixtures/openpose/net/body25.onnx",
        ],
        ext: "onnx",
        run: onnx,
    },
    Target {
        name: "clip_merges",
        seeds: &["fuzz/seeds/clip_merges"],
        ext: "txt",
        run: clip_merges,
    },
    Target {
        name: "diffusers_config",
        seeds: &[
            "crates/gait-diffuse/tests/fixtures/tiny/unet/config.json",
            "crates/gait-diffuse/tests/fixtures/tiny/controlnet/config.json",
            "crates/gait-diffuse/tests/fixtures/tiny/vae/config.json",
            "crates/gait-diffuse/tests/fixtures/tiny/text_encoder/config.json",
        ],
        ext: "json",
        run: diffusers_config,
    },
    Target {
        name: "image",
        seeds: &[
            "crates/gait-edge/tests/fixtures/hed/annotator_safe.png",
            "crates/gait-edge/tests/fixtures/hed/annotator.png",
            "fuzz/seeds/image/sample_frame_96px.jpg",
            // The JPEG reader's cases (libjpeg-turbo, issue 33): progressive, restart
            // markers with an Adobe marker, CMYK, an EXIF orientation, a file cut short.
            "tests/data/jpeg/space_shuttle.jpg",
            "tests/data/jpeg/photoshop-200dpi.jpg",
            "tests/data/jpeg/pil_sample_cmyk.jpg",
            "tests/data/jpeg/hopper_orientation_6.jpg",
            "tests/data/jpeg/truncated_jpeg.jpg",
            "fuzz/seeds/image/testsrc_32x24.bmp",
            "fuzz/seeds/image/testsrc_32x24.tif",
        ],
        ext: "png",
        run: image,
    },
    Target {
        name: "ffprobe_json",
        seeds: &["fuzz/seeds/ffprobe_json"],
        ext: "json",
        run: ffprobe_json,
    },
    Target {
        name: "video_stream",
        seeds: &["fuzz/seeds/video_stream"],
        ext: "rec",
        run: video_stream,
    },
    Target {
        name: "video",
        seeds: &["fuzz/seeds/video"],
        ext: "mp4",
        run: video,
    },
];

/// The target called `name`.
pub fn target(name: &str) -> Option<&'static Target> {
    TARGETS.iter().find(|t| t.name == name)
}
