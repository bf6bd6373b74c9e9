//! Image regenerators implementing [`gait_core::ImageRegenerator`].

mod passthrough;

pub use passthrough::Passthrough;
