//! A shared library that is not a gait plugin: it exports a function, but not
//! `gait_plugin_entry`. The host must refuse it by name.

/// Something else a library might export.
#[unsafe(no_mangle)]
pub extern "C" fn gait_plugin_entry_point_with_a_typo() -> u32 {
    1
}
