//! Pipeline configuration, stage registry, inputs, per-frame cache and runner.
