use std::path::Path;

use crate::error::{CliError, one_line};

/// `gait models`: obtain and list model files.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    action: Action,
}

#[derive(Debug, clap::Subcommand)]
enum Action {
    /// Download a model into the models folder (checksums verified)
    Fetch {
        /// Which model: blazepose
        name: String,
    },
    /// List the models the toolkit knows and whether their files are present
    List,
}

const MODELS: [(&str, &str); 1] = [(
    "blazepose",
    "MediaPipe BlazePose full (from the PyPI wheel mediapipe==0.10.14)",
)];

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    match args.action {
        Action::Fetch { name } => fetch(&name, models_dir),
        Action::List => {
            println!("models folder: {}", models_dir.display());
            for (name, about) in MODELS {
                let present = present(name, models_dir);
                println!(
                    "{name:<12} {} {about}",
                    if present { "present" } else { "missing" }
                );
            }
            Ok(())
        }
    }
}

fn present(name: &str, models_dir: &Path) -> bool {
    let ctx = gait_core::StageContext::new(models_dir);
    match name {
        "blazepose" => gait_pose::blazepose::BlazeposeConfig::default()
            .model_files(&ctx)
            .iter()
            .all(|f| f.is_file()),
        _ => false,
    }
}

fn fetch(name: &str, models_dir: &Path) -> Result<(), CliError> {
    let files = match name {
        "blazepose" => gait_pose::blazepose::fetch::fetch(models_dir)
            .map_err(|e| CliError(one_line(&e.to_string())))?,
        other => {
            let known: Vec<&str> = MODELS.iter().map(|(n, _)| *n).collect();
            return Err(CliError(format!(
                "unknown model `{other}`; known models: {}",
                known.join(", ")
            )));
        }
    };
    for f in files {
        eprintln!("{}", f.display());
    }
    Ok(())
}
