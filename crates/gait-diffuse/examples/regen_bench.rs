//! Per-frame time of the ControlNet regenerator (text encoder once, then per
//! frame: ControlNet + UNet for every step with guidance, VAE decode, image
//! out), as `gait run` uses it. Driven by tools/gpu/bench_regen.sh, which
//! writes random SD 1.5 weights and times diffusers on the same ones.
//!
//! Usage: regen_bench SD_DIR CONTROLNET_DIR EDGES_DIR [key=value ...]
//! keys: device (cpu | cuda | cuda:N), dtype (f32 | f16 | bf16), steps,
//! batch, frames (timed), warmup (untimed), scheduler (unipc | ddim | dpmpp2m),
//! guidance_end, control_guidance_start, control_guidance_end, cache_interval,
//! cache_branch, token_merge_ratio (issue 30's savings), height (resize each
//! edge map to `height` square first), width (then crop it to its middle
//! `width` columns: the subject crop's canvas, e.g. 256 of 512), init (noise | previous: frames one by one, each from the last one's
//! latent) and strength (init = previous).
//! EDGES_DIR holds square grayscale PNG edge maps (white edges on black);
//! frame i uses the (i mod n)-th. Prints one JSON line; with init = previous
//! `first_s` is the first frame's time and `median_s` that of the others.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gait_core::{Device, EdgeMap, Frame, ImageRegenerator, Resize, StageContext};
use gait_diffuse::{ControlnetConfig, ControlnetRegenerator};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

const USAGE: &str = "usage: regen_bench SD_DIR CONTROLNET_DIR EDGES_DIR [device=cuda] [dtype=f16] \
                     [steps=20] [batch=1] [frames=8] [warmup=1] [scheduler=unipc] [guidance_end=1] \
                     [control_guidance_start=0] [control_guidance_end=1] [cache_interval=1] \
                     [cache_branch=0] [token_merge_ratio=0] [height=SIZE] [width=SIZE] [init=noise] [strength=0.5]";

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn run() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err(USAGE.into());
    }
    let mut opts: BTreeMap<String, String> = [
        ("device", "cuda"),
        ("dtype", "f16"),
        ("steps", "20"),
        ("batch", "1"),
        ("frames", "8"),
        ("warmup", "1"),
        ("scheduler", "unipc"),
        ("guidance_end", "1.0"),
        ("control_guidance_start", "0.0"),
        ("control_guidance_end", "1.0"),
        ("cache_interval", "1"),
        ("cache_branch", "0"),
        ("token_merge_ratio", "0.0"),
        ("width", "0"),
        ("height", "0"),
        ("init", "noise"),
        ("strength", "0.5"),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    for kv in &args[3..] {
        let (k, v) = kv
            .split_once('=')
            .ok_or_else(|| format!("`{kv}`: expected key=value; {USAGE}"))?;
        if !opts.contains_key(k) {
            return Err(format!("unknown key `{k}`; {USAGE}").into());
        }
        opts.insert(k.to_string(), v.to_string());
    }
    let num = |k: &str| -> Res<usize> { Ok(opts[k].parse().map_err(|e| format!("{k}: {e}"))?) };
    let device: Device = opts["device"].parse()?;
    let (steps, batch, frames, warmup) =
        (num("steps")?, num("batch")?, num("frames")?, num("warmup")?);
    let edges = read_edges(Path::new(&args[2]))?;
    let edges: Vec<image::GrayImage> = match num("height")? {
        0 => edges,
        h => edges
            .iter()
            .map(|e| image::imageops::resize(e, h as u32, h as u32, image::imageops::Triangle))
            .collect(),
    };
    let size = edges[0].width();
    let width = match num("width")? {
        0 => size,
        w => w as u32,
    };
    let edges: Vec<image::GrayImage> = edges.iter().map(|e| middle_columns(e, width)).collect();
    let previous = opts["init"] == "previous";
    // Each frame starts from the last: one at a time, and the first is not like the others.
    let batch = if previous { 1 } else { batch };

    // Everything else (prompts, guidance 7.5, conditioning scale 1, seeds)
    // stays at the regenerator's defaults, the paper's settings.
    let config: ControlnetConfig = toml_config(&format!(
        "sd_path = {:?}\ncontrolnet_path = {:?}\ndtype = {:?}\nsteps = {steps}\nbatch = {batch}\n\
         resolution = {}\nscheduler = {:?}\nguidance_end = {}\ncontrol_guidance_start = {}\n\
         control_guidance_end = {}\ncache_interval = {}\ncache_branch = {}\ntoken_merge_ratio = {}\n\
         region = {:?}\ncrop_size = [{width}, {size}]\ninit = {:?}\n{}",
        abs(&args[0])?,
        abs(&args[1])?,
        opts["dtype"],
        width.min(size),
        opts["scheduler"],
        opts["guidance_end"],
        opts["control_guidance_start"],
        opts["control_guidance_end"],
        opts["cache_interval"],
        opts["cache_branch"],
        opts["token_merge_ratio"],
        if width == size { "frame" } else { "subject" },
        opts["init"],
        if previous {
            format!("strength = {}\n", opts["strength"])
        } else {
            String::new()
        },
    ))?;
    let ctx = StageContext::new(".").on(device);
    let t0 = Instant::now();
    let mut regen = ControlnetRegenerator::new(&config, &ctx)?;
    let load_s = t0.elapsed().as_secs_f64();

    let mut per_frame = Vec::new();
    let mut index = 0;
    for call in 0..(warmup + frames.div_ceil(batch)) {
        let (fs, es): (Vec<Frame>, Vec<EdgeMap>) = (0..batch)
            .map(|_| {
                let e = &edges[index % edges.len()];
                index += 1;
                let rgb = image::DynamicImage::ImageLuma8(e.clone()).to_rgb8();
                (
                    Frame::new(index, rgb),
                    EdgeMap {
                        index,
                        image: e.clone(),
                        resize: Resize::identity(width, size),
                    },
                )
            })
            .unzip();
        let t = Instant::now();
        let out = regen.regenerate(&fs, Some(&es))?;
        let s = t.elapsed().as_secs_f64();
        if out.len() != batch {
            return Err(format!("{} frames in, {} out", batch, out.len()).into());
        }
        if call >= warmup {
            per_frame.extend(std::iter::repeat_n(s / batch as f64, batch));
        }
    }
    per_frame.truncate(frames);
    // With init = previous the first frame starts from noise: timed apart.
    let first = per_frame[0];
    let steady = if previous && per_frame.len() > 1 {
        &per_frame[1..]
    } else {
        &per_frame[..]
    };
    let mut sorted = steady.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    println!(
        "{{\"impl\": \"gait\", \"device\": \"{device}\", \"dtype\": {:?}, \"steps\": {steps}, \"batch\": {batch}, \
         \"scheduler\": {:?}, \"guidance_end\": {}, \"control_guidance\": [{}, {}], \
         \"size\": {size}, \"width\": {width}, \"cache_interval\": {}, \"cache_branch\": {}, \
         \"token_merge_ratio\": {}, \"init\": {:?}, \"load_s\": {load_s:.3}, \"first_s\": {first:.4}, \
         \"median_s\": {median:.4}, \"per_frame_s\": {:?}}}",
        opts["dtype"],
        opts["scheduler"],
        opts["guidance_end"],
        opts["control_guidance_start"],
        opts["control_guidance_end"],
        opts["cache_interval"],
        opts["cache_branch"],
        opts["token_merge_ratio"],
        opts["init"],
        per_frame
            .iter()
            .map(|s| (s * 1e4).round() / 1e4)
            .collect::<Vec<_>>()
    );
    Ok(())
}

/// The middle `width` columns of a square edge map (all of it when `width` is its size).
fn middle_columns(e: &image::GrayImage, width: u32) -> image::GrayImage {
    let x0 = (e.width().saturating_sub(width)) / 2;
    image::imageops::crop_imm(e, x0, 0, width.min(e.width()), e.height()).to_image()
}

fn toml_config(text: &str) -> Res<ControlnetConfig> {
    Ok(toml::from_str(text)?)
}

fn abs(p: &str) -> Res<PathBuf> {
    Ok(std::fs::canonicalize(p).map_err(|e| format!("{p}: {e}"))?)
}

/// The square grayscale PNGs of `dir`, sorted by name.
fn read_edges(dir: &Path) -> Res<Vec<image::GrayImage>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    paths.sort();
    let edges = paths
        .iter()
        .map(|p| {
            Ok(image::open(p)
                .map_err(|e| format!("{}: {e}", p.display()))?
                .to_luma8())
        })
        .collect::<Res<Vec<_>>>()?;
    match edges.first() {
        None => Err(format!("{}: no .png edge maps", dir.display()).into()),
        Some(e)
            if edges
                .iter()
                .any(|x| x.dimensions() != (e.width(), e.width())) =>
        {
            Err(format!(
                "{}: edge maps must be square and of one size",
                dir.display()
            )
            .into())
        }
        Some(_) => Ok(edges),
    }
}
