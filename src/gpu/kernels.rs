//! Kernel composition (`common.wgsl` prepended to each stage) and naga validation.

use crate::plan::Pass;

/// The shared structs and helpers.
pub const COMMON_WGSL: &str = include_str!("../../kernels/common.wgsl");

/// The complete WGSL source of a stage.
pub fn compose(pass: Pass) -> String {
    format!("{COMMON_WGSL}\n{}", pass.kernel_source())
}

/// Parses and validates a WGSL source with naga; errors come formatted with line and caret.
pub fn validate_wgsl(label: &str, source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| e.emit_to_string_with_path(source, label))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string_with_path(source, label))?;
    Ok(module)
}
