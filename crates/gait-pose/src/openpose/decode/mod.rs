//! Turning heatmaps and part-affinity fields into people.
