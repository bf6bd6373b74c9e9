//! Where the model stages run: `[run] device = "cpu" | "cuda" | "cuda:N"`.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The processor a stage runs its model on. Stages without a model (canny,
/// passthrough) always run on the CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Device {
    #[default]
    Cpu,
    /// The CUDA GPU of this ordinal; `"cuda"` alone is GPU 0.
    Cuda(u32),
}

impl Device {
    pub fn is_cpu(self) -> bool {
        self == Device::Cpu
    }

    /// The candle device: the CPU, or the GPU when candle was built with
    /// CUDA (the workspace's `cuda` feature), else [`NoCudaSupport`].
    #[cfg(feature = "candle")]
    pub fn candle(self) -> Result<candle_core::Device, crate::StageError> {
        match self {
            Device::Cpu => Ok(candle_core::Device::Cpu),
            Device::Cuda(_) if !candle_core::utils::cuda_is_available() => {
                Err(NoCudaSupport.into())
            }
            Device::Cuda(n) => candle_core::Device::new_cuda(n as usize).map_err(|e| {
                // candle appends a multi-line backtrace when one was captured;
                // the message stays one line.
                let e = match e {
                    candle_core::Error::WithBacktrace { inner, .. } => *inner,
                    e => e,
                };
                crate::StageError::backend(
                    "candle",
                    format!("cannot use CUDA device {n} ({e}); check the GPU and its driver with nvidia-smi"),
                )
            }),
        }
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Device::Cpu => f.write_str("cpu"),
            Device::Cuda(n) => write!(f, "cuda:{n}"),
        }
    }
}

impl FromStr for Device {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!("unknown device `{s}`; valid: \"cpu\", \"cuda\", \"cuda:N\" (N = GPU number)")
        };
        match s {
            "cpu" => Ok(Device::Cpu),
            "cuda" => Ok(Device::Cuda(0)),
            _ => s
                .strip_prefix("cuda:")
                .and_then(|n| n.parse().ok())
                .map(Device::Cuda)
                .ok_or_else(bad),
        }
    }
}

impl Serialize for Device {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Device {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        String::deserialize(d)?
            .parse()
            .map_err(serde::de::Error::custom)
    }
}

/// A GPU was asked for but this binary was built without CUDA.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("this build has no CUDA support: rebuild with `--features cuda` (README, GPU section)")]
pub struct NoCudaSupport;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_three_forms_and_names_the_valid_ones() {
        assert_eq!("cpu".parse(), Ok(Device::Cpu));
        assert_eq!("cuda".parse(), Ok(Device::Cuda(0)));
        assert_eq!("cuda:3".parse(), Ok(Device::Cuda(3)));
        for bad in ["gpu", "cuda:", "cuda:x", "CUDA", "cuda:-1"] {
            let e = bad.parse::<Device>().unwrap_err();
            assert!(e.contains(bad) && e.contains("cuda:N"), "{e}");
        }
    }

    #[test]
    fn round_trips_through_its_text() {
        for d in [Device::Cpu, Device::Cuda(0), Device::Cuda(7)] {
            assert_eq!(d.to_string().parse(), Ok(d));
        }
        assert_eq!(Device::Cuda(0).to_string(), "cuda:0");
    }
}
