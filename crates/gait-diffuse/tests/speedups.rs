//! DeepCache and token merging on the tiny random models against stock PyPI
//! `deepcache` 0.1.1 (`DeepCacheSDHelper`) and `tomesd` 0.1.3 on diffusers'
//! ControlNet pipelines, and the start from a previous frame's latent
//! (`init = "previous"`) against diffusers' img2img pipeline handed those
//! latents (fixtures from tools/diffuse/make_speedup_fixtures.py, same noise
//! and the same SplitMix64 stream of merge picks on both sides), each with a
//! mutation that must break the match.

mod common;

use candle_core::{Device, Tensor};
use common::{assert_close, fixtures, modes, modes_control, paper_context, rel_err};
use gait_diffuse::{ControlnetPipeline, Cutoffs, DenoiseParams, Savings, SchedulerKind};
use serde_json::Value;

const TOL: f64 = 1e-4;

fn pipeline() -> ControlnetPipeline {
    common::tiny_pipeline_with_encoder()
}

fn cases() -> Vec<Value> {
    let text = std::fs::read_to_string(fixtures().join("speedups.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn images() -> std::collections::HashMap<String, Tensor> {
    candle_core::safetensors::load(fixtures().join("speedups.safetensors"), &Device::Cpu).unwrap()
}

fn params(c: &Value) -> DenoiseParams {
    let f = |k: &str| c[k].as_f64().unwrap();
    let u = |k: &str| c[k].as_u64().unwrap();
    DenoiseParams {
        steps: u("steps") as usize,
        guidance_scale: f("guidance_scale"),
        conditioning_scale: f("conditioning_scale"),
        scheduler: serde_json::from_value::<SchedulerKind>(c["scheduler"].clone()).unwrap(),
        cutoffs: Cutoffs {
            guidance_end: f("guidance_end"),
            control_start: f("control_start"),
            control_end: f("control_end"),
        },
        savings: Savings {
            cache_interval: u("cache_interval") as usize,
            cache_branch: u("cache_branch") as usize,
            token_merge_ratio: f("token_merge_ratio"),
            merge_seed: u("merge_seed"),
        },
    }
}

/// Our image for case `c` with settings `p` (the case's, or a mutation).
fn run(pipe: &ControlnetPipeline, c: &Value, p: &DenoiseParams) -> Tensor {
    let e = modes();
    let ctx = paper_context(pipe);
    let name = c["name"].as_str().unwrap();
    let (control, noise) = if c["height"].as_u64() == Some(64) {
        (modes_control(&e), e["modes.noise"].clone())
    } else {
        let img = images();
        let edge = (&img[&format!("{name}.edge")] / 255.0).unwrap();
        let control = Tensor::stack(&[&edge, &edge, &edge], 0)
            .unwrap()
            .unsqueeze(0)
            .unwrap();
        (control, img[&format!("{name}.noise")].clone())
    };
    if c["init"] == "previous" {
        let start = &images()[&format!("{name}.start")];
        let strength = c["strength"].as_f64().unwrap();
        return pipe
            .from_latents(&ctx, &control, start, &noise, strength, p)
            .unwrap()
            .images;
    }
    match c["mode"].as_str().unwrap() {
        "text2img" => pipe.generate(&ctx, &control, &noise, p),
        _ => {
            let hwc = (&e["modes.frame"] / 255.0).unwrap();
            let init = ((hwc.permute((2, 0, 1)).unwrap().unsqueeze(0).unwrap() * 2.0).unwrap()
                - 1.0)
                .unwrap();
            let strength = c["strength"].as_f64().unwrap();
            pipe.img2img(
                &ctx,
                &control,
                &init,
                &e["modes.enc_eps"],
                &noise,
                strength,
                p,
            )
        }
    }
    .unwrap()
}

fn want(c: &Value) -> Tensor {
    images()[&format!("{}.image", c["name"].as_str().unwrap())].clone()
}

#[test]
fn every_case_matches_deepcache_tomesd_and_img2img_from_latents() {
    let pipe = pipeline();
    let cases = cases();
    assert_eq!(cases.len(), 15, "speedups.json lists every case");
    for c in &cases {
        let img = run(&pipe, c, &params(c));
        assert_close(c["name"].as_str().unwrap(), &img, &want(c), TOL);
    }
}

/// The mutations the parity test must catch: each is far outside its tolerance.
fn assert_breaks(label: &str, pipe: &ControlnetPipeline, c: &Value, p: &DenoiseParams) {
    let e = rel_err(&run(pipe, c, p), &want(c));
    println!("{label}: relative error {e:.3e}");
    assert!(e > 100.0 * TOL, "{label} still matches ({e:.3e})");
}

#[test]
fn a_cache_interval_off_by_one_or_another_branch_fails_the_match() {
    let pipe = pipeline();
    let cases = cases();
    let c = cases
        .iter()
        .find(|c| c["name"] == "dc_t2i_i3_b1_unipc")
        .unwrap();
    let mut p = params(c);
    p.savings.cache_interval += 1;
    assert_breaks("interval + 1", &pipe, c, &p);
    p.savings.cache_interval -= 2;
    assert_breaks("interval - 1", &pipe, c, &p);
    let mut p = params(c);
    p.savings.cache_branch = 0;
    assert_breaks("branch 0 for 1", &pipe, c, &p);
}

#[test]
fn a_changed_merge_ratio_or_seed_fails_the_match() {
    let pipe = pipeline();
    let cases = cases();
    let c = cases.iter().find(|c| c["name"] == "tome_r05_ddim").unwrap();
    let mut p = params(c);
    p.savings.token_merge_ratio = 0.4;
    assert_breaks("ratio 0.4 for 0.5", &pipe, c, &p);
    let mut p = params(c);
    p.savings.merge_seed += 1;
    assert_breaks("merge seed + 1", &pipe, c, &p);
}

#[test]
fn a_changed_strength_or_start_fails_the_previous_latent_match() {
    let pipe = pipeline();
    let cases = cases();
    let c = cases.iter().find(|c| c["name"] == "prev_ddim").unwrap();
    let mut changed = c.clone();
    changed["strength"] = serde_json::json!(0.7);
    assert_breaks("strength 0.7 for 0.5", &pipe, &changed, &params(c));
    // The preset's combination: its savings off must not match either.
    let c = cases.iter().find(|c| c["name"] == "prev_cpu").unwrap();
    let mut p = params(c);
    p.savings = Savings::default();
    let e = rel_err(&run(&pipe, c, &p), &want(c));
    println!("prev_cpu without savings: relative error {e:.3e}");
    assert!(e > 10.0 * TOL, "savings off still match ({e:.3e})");
}
