//! Kernel composition (`common.wgsl` prepended to each stage) and naga validation.

use super::implicit::SolveKernel;
use crate::plan::Pass;

/// The shared structs and helpers.
pub const COMMON_WGSL: &str = include_str!("../../kernels/common.wgsl");

/// A deforming body's contact by inverse skinning, composed after the stages that collide.
pub const DEFORMED_BODY_WGSL: &str = include_str!("../../kernels/deformed_body.wgsl");

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
    /// The orthotropic membrane (implicit Euler's membrane terms).
    pub membrane: bool,
}

impl VbdEnergies {
    /// Every combination, for validation.
    pub const ALL: [VbdEnergies; 16] = {
        let mut all = [VbdEnergies {
            bending: false,
            seams: false,
            body: false,
            membrane: false,
        }; 16];
        let mut k = 0;
        while k < 16 {
            all[k] = VbdEnergies {
                bending: k & 1 != 0,
                seams: k & 2 != 0,
                body: k & 4 != 0,
                membrane: k & 8 != 0,
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
    compose_with(pass, input, VbdEnergies::ALL[15])
}

/// `compose`, keeping only the sections of the energies in `energies`. Dropped lines become
/// empty lines, so line numbers in errors still match the stage file. `vbd_solve` is a kernel
/// of implicit Euler's solve, composed with the solve's shared files (`SolveKernel::compose`).
pub fn compose_with(pass: Pass, input: ForceInput, energies: VbdEnergies) -> String {
    if pass == Pass::VbdSolve {
        return SolveKernel::Sweep.compose(energies).source;
    }
    let tail = if pass.reads_forces() {
        input.wgsl()
    } else {
        ""
    };
    let enabled = |name: &str| match name {
        "bending" => energies.bending,
        "seams" => energies.seams,
        "body" => energies.body,
        "membrane" => energies.membrane,
        _ => true,
    };
    let body = keep_sections(pass.kernel_source(), enabled);
    let deformed = match pass {
        Pass::CollideBody => DEFORMED_BODY_WGSL,
        _ => "",
    };
    format!("{COMMON_WGSL}\n{body}\n{tail}{deformed}")
}

/// `source` with its optional sections resolved: a `// section NAME` … `// else NAME` …
/// `// end NAME` block keeps the section when `enabled(NAME)` and the `else` part when not.
/// Dropped lines (and the markers) become empty lines, so line numbers stay those of the file.
pub fn keep_sections(source: &str, enabled: impl Fn(&str) -> bool) -> String {
    let mut body = String::new();
    // None: outside any section; Some(keep): inside a section or its else part.
    let mut keep: Option<bool> = None;
    for line in source.lines() {
        let t = line.trim();
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
    body
}

/// A WGSL module composed of several files, one after another, remembering where each starts
/// so that an error can name the file and line it comes from.
#[derive(Clone, Debug, Default)]
pub struct Composed {
    /// The module's source.
    pub source: String,
    /// Each file's name (in `kernels/`, without `.wgsl`) and its first line in `source`
    /// (1-based).
    pub files: Vec<(&'static str, usize)>,
}

impl Composed {
    /// Appends a file's text.
    pub fn push(&mut self, file: &'static str, text: String) {
        self.files.push((file, self.source.lines().count() + 1));
        self.source.push_str(&text);
        if !text.ends_with('\n') {
            self.source.push('\n');
        }
    }

    /// The file and its line (1-based) of the module's line `line`.
    pub fn locate(&self, line: usize) -> (&'static str, usize) {
        let (file, first) = (self.files.iter())
            .rev()
            .find(|(_, first)| *first <= line)
            .copied()
            .unwrap_or(("?", 1));
        (file, line - first + 1)
    }

    /// Validates the module with naga; an error names `kernels/FILE.wgsl:LINE:COLUMN` of the
    /// file the offending line comes from.
    pub fn validate(&self, label: &str) -> Result<naga::Module, String> {
        validate_wgsl(label, &self.source).map_err(|report| {
            let prefix = format!("{label}:");
            let mut out = String::new();
            let mut rest = report.as_str();
            while let Some(at) = rest.find(&prefix) {
                out.push_str(&rest[..at]);
                let after = &rest[at + prefix.len()..];
                let digits = after.bytes().take_while(u8::is_ascii_digit).count();
                match after[..digits].parse::<usize>() {
                    Ok(line) => {
                        let (file, local) = self.locate(line);
                        out.push_str(&format!("kernels/{file}.wgsl:{local}"));
                    }
                    Err(_) => out.push_str(&prefix),
                }
                rest = &after[digits..];
            }
            out.push_str(rest);
            format!("{label}\n{out}")
        })
    }
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
