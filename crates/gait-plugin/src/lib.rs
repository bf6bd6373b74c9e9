//! Stages loaded at run time from shared libraries (`kind = "plugin"`).
//!
//! - Host side: [`PluginConfig`] (the stage table) and [`load_edge_detector`],
//!   [`load_regenerator`], [`load_pose_estimator`], which open the library,
//!   check the ABI version and stage family, and return a normal stage object
//!   that checks everything the plugin returns.
//! - Plugin side: implement a gait-core stage trait plus [`PluginStage`] and
//!   export it with [`export_edge_detector!`], [`export_regenerator!`] or
//!   [`export_pose_estimator!`] in a `cdylib` crate. The macros write the C
//!   side and catch panics.
//! - The C ABI itself, for plugins in other languages: [`abi`].
//!
//! The guide is `docs/adding-a-stage.md`.

pub mod abi;
mod config;
mod error;
#[doc(hidden)]
pub mod export;
mod library;
mod output;
mod stages;

pub use config::PluginConfig;
pub use error::PluginError;
pub use export::PluginStage;
pub use stages::{load_edge_detector, load_pose_estimator, load_regenerator};

/// Exports `$t` (an `EdgeDetector + PluginStage`) as this library's plugin.
/// Use once per `cdylib` crate.
#[macro_export]
macro_rules! export_edge_detector {
    ($t:ty) => {
        $crate::__export_plugin!($t, edge_descriptor);
    };
}

/// Exports `$t` (an `ImageRegenerator + PluginStage`) as this library's plugin.
#[macro_export]
macro_rules! export_regenerator {
    ($t:ty) => {
        $crate::__export_plugin!($t, regenerator_descriptor);
    };
}

/// Exports `$t` (a `PoseEstimator + PluginStage`) as this library's plugin.
#[macro_export]
macro_rules! export_pose_estimator {
    ($t:ty) => {
        $crate::__export_plugin!($t, pose_descriptor);
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __export_plugin {
    ($t:ty, $descriptor:ident) => {
        /// The gait plugin entry point (see `gait_plugin::abi`).
        #[unsafe(no_mangle)]
        pub extern "C" fn gait_plugin_entry() -> *const $crate::abi::GaitPluginDescriptor {
            static DESCRIPTOR: $crate::abi::GaitPluginDescriptor =
                $crate::export::$descriptor::<$t>(concat!(
                    env!("CARGO_PKG_NAME"),
                    " ",
                    env!("CARGO_PKG_VERSION")
                ));
            &DESCRIPTOR
        }
    };
}
