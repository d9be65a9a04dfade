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

/// The optional energies of `vbd_solve` (and `integrate`'s bending gather): their
/// `// section NAME` … `// else NAME` … `// end NAME` blocks keep the section when the scene
/// has the energy and the `else` part when not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VbdEnergies {
    /// Dihedral hinges.
    pub bending: bool,
    /// Seam pairs.
    pub seams: bool,
    /// Body contact.
    pub body: bool,
}

impl VbdEnergies {
    /// Every combination, for validation.
    pub const ALL: [VbdEnergies; 8] = {
        let mut all = [VbdEnergies {
            bending: false,
            seams: false,
            body: false,
        }; 8];
        let mut k = 0;
        while k < 8 {
            all[k] = VbdEnergies {
                bending: k & 1 != 0,
                seams: k & 2 != 0,
                body: k & 4 != 0,
            };
            k += 1;
        }
        all
    };
}

/// The complete WGSL source of a stage, with every optional section in. Stages that read the
/// forces summed so far get `previous_force` from `input` (appended, so that line numbers in
/// the stage file stay offset by `common.wgsl` only).
pub fn compose(pass: Pass, input: ForceInput) -> String {
    compose_with(pass, input, VbdEnergies::ALL[7])
}

/// `compose`, keeping only the sections of the energies in `energies`. Dropped lines become
/// empty lines, so line numbers in errors still match the stage file.
pub fn compose_with(pass: Pass, input: ForceInput, energies: VbdEnergies) -> String {
    let tail = if pass.reads_forces() {
        input.wgsl()
    } else {
        ""
    };
    let mut body = String::new();
    // None: outside any section; Some(keep): inside a section or its else part.
    let mut keep: Option<bool> = None;
    for line in pass.kernel_source().lines() {
        let t = line.trim();
        let enabled = |name: &str| match name {
            "bending" => energies.bending,
            "seams" => energies.seams,
            "body" => energies.body,
            _ => true,
        };
        let marker = if let Some(name) = t.strip_prefix("// section ") {
            keep = Some(enabled(name));
            true
        } else if let Some(name) = t.strip_prefix("// else ") {
            keep = Some(!enabled(name));
            true
        } else if t.starts_with("// end ") {
            keep = None;
            true
        } else {
            false
        };
        if !marker && keep.unwrap_or(true) {
            body.push_str(line);
        }
        body.push('\n');
    }
    format!("{COMMON_WGSL}\n{body}\n{tail}")
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
