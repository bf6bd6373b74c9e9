//! `gait`: markerless gait analysis for lower-limb prosthetic users.

mod commands;
mod error;
mod hub;
mod interrupt;
mod malloc_tuning;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::error::CliError;

/// Markerless gait analysis of lower-limb prosthetic users from ordinary video.
///
/// Pipeline: frames -> edge map -> regenerated frame (ControlNet) -> pose ->
/// filtered keypoints -> joint angles -> gait cycles -> report.
#[derive(Debug, Parser)]
#[command(name = "gait", version, about, long_about = None)]
struct Cli {
    /// Folder with model files [default: $GAIT_MODELS_DIR, else ~/.cache/gait/models]
    #[arg(long, global = true, value_name = "DIR")]
    models_dir: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the pipeline on a video, an image folder or an image.
    Run(commands::run::Args),
    /// Write the edge map of every frame as a PNG.
    Edges(commands::edges::Args),
    /// Angles, gait events and cycles from a keypoints CSV.
    Kin(commands::kin::Args),
    /// Score predicted keypoints and angles against ground truth.
    Eval(commands::eval::Args),
    /// Obtain and list model files.
    Models(commands::models::Args),
    /// Run every combination of stage choices over videos and compare them.
    Ablate(commands::ablate::Args),
    /// Write an earlier run's results as c3d, OpenSim (.trc/.mot) or OpenPose JSON.
    Export(commands::export::Args),
    /// Look at a run frame by frame in the browser and save corrections.toml.
    Review(commands::review::Args),
    /// Run a study (one video per row) locally or on Slurm, and gather a cohort table.
    Batch(commands::batch::Args),
    /// A patient's visit: passes from the left, right, front and back in one report.
    Visit(commands::visit::Args),
    /// A subject's visits side by side: which differences are changes.
    Progress(commands::progress::Args),
}

fn main() -> ExitCode {
    gait_pipeline::timings::mark_process_start();
    malloc_tuning::keep_frame_buffers();
    let cli = Cli::parse();
    let models_dir = commands::models_dir(cli.models_dir);
    let result: Result<(), CliError> = match cli.command {
        Command::Run(args) => commands::run::execute(args, &models_dir),
        Command::Kin(args) => commands::kin::execute(args, &models_dir),
        Command::Edges(args) => commands::edges::execute(args, &models_dir),
        Command::Ablate(args) => commands::ablate::execute(args, &models_dir),
        Command::Eval(args) => commands::eval::execute(args, &models_dir),
        Command::Models(args) => commands::models::execute(args, &models_dir),
        Command::Export(args) => commands::export::execute(args),
        Command::Review(args) => commands::review::execute(args),
        Command::Visit(args) => commands::visit::execute(args, &models_dir),
        Command::Progress(args) => commands::progress::execute(args),
        Command::Batch(args) => match commands::batch::execute(args, &models_dir) {
            Ok(code) => return code,
            Err(e) => Err(e),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error::one_line(&e.message));
            ExitCode::from(interrupt::exit_code().unwrap_or(e.code))
        }
    }
}
