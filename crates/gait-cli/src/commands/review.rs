use std::path::PathBuf;

use gait_review::{ReviewSource, ServeOptions};

use crate::error::{CliError, one_line};

/// `gait review`: a local page to look at a run and save corrections.toml.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["run_dir", "keypoints"])))]
pub struct Args {
    /// A `gait run` output folder
    #[arg(value_name = "RUN_DIR")]
    run_dir: Option<PathBuf>,
    /// Review a keypoints CSV (DeepLabCut layout) instead of a run folder; needs --fps unless
    /// run.json is beside it (a run's keypoints.csv)
    #[arg(long, value_name = "FILE")]
    keypoints: Option<PathBuf>,
    /// The video the keypoints come from [default for a run: the input run.json names]
    #[arg(long, value_name = "FILE")]
    video: Option<PathBuf>,
    /// Frame rate of the keypoints (with --keypoints)
    #[arg(long, value_name = "N")]
    fps: Option<f64>,
    /// Pipeline config whose [postprocess] and [kinematics] apply (with --keypoints) [default: the
    /// run.json beside the keypoints, else configs/default.toml]
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Where corrections are saved (with --keypoints) [default: corrections.toml beside the keypoints]
    #[arg(long, value_name = "FILE")]
    corrections: Option<PathBuf>,
    /// Port on 127.0.0.1 [default: the run folder's own, which its report's frame links open,
    /// else a free one]
    #[arg(long, value_name = "N")]
    port: Option<u16>,
    /// Open the page in the system browser
    #[arg(long)]
    open: bool,
    /// Open at this frame (e.g. one the checklist names) [default: the first walking bout's]
    #[arg(long, value_name = "N")]
    frame: Option<usize>,
}

pub fn execute(args: Args) -> Result<(), CliError> {
    let fail = |e: gait_review::ReviewError| CliError::new(one_line(&e.to_string()));
    let src = match (&args.run_dir, &args.keypoints) {
        (Some(dir), _) => {
            if args.config.is_some() || args.corrections.is_some() || args.fps.is_some() {
                return Err(CliError::new(
                    "--config, --corrections and --fps go with --keypoints; a run folder has its own (run.json, corrections.toml)",
                ));
            }
            ReviewSource::from_run_dir(dir, args.video.as_deref()).map_err(fail)?
        }
        (None, Some(kp)) => {
            let beside = gait_pipeline::RunBeside::find(kp)?;
            let fps = super::frame_rate(args.fps, beside.as_ref(), kp)?;
            ReviewSource::from_keypoints(
                kp,
                args.video.as_deref(),
                fps,
                args.config.as_deref(),
                args.corrections.as_deref(),
            )
            .map_err(fail)?
        }
        (None, None) => {
            return Err(CliError::new(
                "give a run folder (gait review RUN_DIR) or --keypoints FILE --fps N",
            ));
        }
    };
    if let Err(why) = &src.video {
        eprintln!("warning: {why}");
    }
    // A run folder's own port, or that of the folder of the keypoints (a `gait kin` output).
    let folder = args
        .run_dir
        .clone()
        .or_else(|| {
            args.keypoints
                .as_ref()
                .and_then(|k| k.parent().map(|p| p.to_path_buf()))
        })
        .map(|d| {
            if d.as_os_str().is_empty() {
                ".".into()
            } else {
                d
            }
        });
    let opts = ServeOptions {
        port: args.port,
        link_port: folder.as_deref().map(gait_checklist::review_port),
        open: args.open,
        frame: args.frame,
    };
    gait_review::serve(src, &opts).map_err(fail)
}
