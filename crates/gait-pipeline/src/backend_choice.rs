//! `backend = "auto"`: a model stage runs on the faster backend available
//! here, ONNX Runtime when its library loads, else candle (BENCHMARKS.md:
//! BlazePose on ONNX Runtime takes about half candle's time per frame on
//! x86-64). Decided once when the config is read, so the resolved config in
//! run.json names the backend that ran and `--config run.json` repeats it.

use gait_core::Backend;

use crate::PipelineConfig;

/// Decides every `auto` backend of `config`; one line per decision
/// ("pose: auto -> ort: ...") for run.json.
pub(crate) fn decide(config: &mut PipelineConfig) -> Vec<String> {
    use gait_diffuse::RegeneratorConfig as R;
    use gait_edge::EdgeConfig as E;
    use gait_pose::PoseConfig as P;
    let mut backends: Vec<(&str, &mut Backend)> = Vec::new();
    if let E::Hed(c) = &mut config.edge {
        backends.push(("edge", &mut c.backend));
    }
    if let R::Controlnet(c) = &mut config.regenerator {
        backends.push(("regenerator", &mut c.backend));
    }
    match &mut config.pose {
        P::Blazepose(c) => backends.push(("pose", &mut c.backend)),
        P::Openpose(c) => backends.push(("pose", &mut c.backend)),
        P::Plugin(_) | P::Python(_) => {}
    }
    let gpu = !config.run.device.is_cpu();
    let mut notes = Vec::new();
    for (stage, backend) in backends {
        let (chosen, why) = backend.decide(|| {
            if gpu {
                // ONNX Runtime on a GPU needs the onnxruntime-gpu library; candle is what
                // `[run] device` set up (BlazePose on candle stays on the CPU).
                return Err("a GPU run: ort there needs the onnxruntime-gpu library, set backend = \"ort\" for it".into());
            }
            gait_ort::environment().map(|_| ())
        });
        if let Some(why) = why {
            notes.push(format!("{stage}: auto -> {chosen}: {why}"));
        }
        *backend = chosen;
    }
    notes
}
