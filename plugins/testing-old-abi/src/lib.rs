//! A plugin built for another ABI version: only the version header is
//! meaningful, as the host must stop reading after it.

use gait_plugin::abi::ABI_VERSION;

/// What a plugin of ABI version `ABI_VERSION + 1` might start with; the
/// host must not read past `abi_version`.
#[repr(C)]
pub struct OtherVersionDescriptor {
    pub abi_version: u32,
    pub something_new: u32,
}

static DESCRIPTOR: OtherVersionDescriptor = OtherVersionDescriptor {
    abi_version: ABI_VERSION + 1,
    something_new: 0xdead_beef,
};

/// The entry point, with the other version's descriptor.
#[unsafe(no_mangle)]
pub extern "C" fn gait_plugin_entry() -> *const OtherVersionDescriptor {
    &DESCRIPTOR
}
