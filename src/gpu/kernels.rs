//! Kernel composition (`common.wgsl` prepended to each stage) and naga validation.

use crate::plan::Pass;

/// The shared structs and helpers.
pub const COMMON_WGSL: &str = include_str!("../../kernels/common.wgsl");

/// Where a force stage finds the forces that earlier stages of the substep summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForceInput {
    /// The first force stage of a substep starts from zero and binds no input.
    Zero,
    /// Later force stages read the previous stage's output at `@group(1) @binding(0)`.
    Texture,
}

impl ForceInput {
    /// Both variants, for validation.
    pub const ALL: [ForceInput; 2] = [ForceInput::Zero, ForceInput::Texture];

    fn wgsl(self) -> &'static str {
        match self {
            ForceInput::Zero => {
                "fn previous_force(i: u32) -> vec3<f32> {\n    return vec3<f32>(0.0);\n}\n"
            }
            ForceInput::Texture => {
                "@group(1) @binding(0) var force_in: texture_2d<f32>;\n\
                 fn previous_force(i: u32) -> vec3<f32> {\n    \
                 return textureLoad(force_in, texel(i), 0).xyz;\n}\n"
            }
        }
    }
}

/// The complete WGSL source of a stage. Force stages get `previous_force` from `input`
/// (appended, so that line numbers in the stage file stay offset by `common.wgsl` only);
/// `integrate` ignores it.
pub fn compose(pass: Pass, input: ForceInput) -> String {
    let tail = if pass.is_force() { input.wgsl() } else { "" };
    format!("{COMMON_WGSL}\n{}\n{tail}", pass.kernel_source())
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
