//! Implicit Euler's solve on the GPU: its kernels validate and bind what they declare, their
//! shared structs match the Rust mirrors, and on lavapipe every stage matches its CPU twin
//! from identical inputs, and a small sewn garment's trajectory matches the CPU's.

mod common;

use drapekit::gpu::implicit::layout::{OpParams, SolveControl, SolveScalars};
use drapekit::gpu::implicit::SolveKernel;
use drapekit::gpu::kernels::{validate_wgsl, VbdEnergies};
use std::mem::{offset_of, size_of};

/// The energies' section combinations the solve kernels compose (contact is never a section
/// of theirs).
fn section_variants() -> impl Iterator<Item = VbdEnergies> {
    VbdEnergies::ALL.into_iter().filter(|e| !e.body)
}

#[test]
fn naga_validates_every_solve_kernel() {
    for kernel in SolveKernel::ALL {
        for energies in section_variants() {
            let composed = kernel.compose(energies);
            let label = format!("{} ({energies:?})", kernel.file());
            if let Err(report) = composed.validate(&label) {
                panic!("{report}");
            }
        }
    }
}

#[test]
fn solve_kernel_errors_name_the_file_and_line() {
    // A composed module's error points into the file the line came from.
    let mut composed = SolveKernel::PcgStart.compose(VbdEnergies::ALL[0]);
    let before = composed.source.lines().count();
    composed.push("broken", "fn oops() { let x: f32 = 1u; }\n".into());
    let report = composed.validate("broken kernel").unwrap_err();
    assert!(report.contains("kernels/broken.wgsl:1:"), "{report}");
    assert!(!report.contains(&format!(":{}:", before + 1)), "{report}");
}

#[test]
fn solve_kernels_bind_what_they_declare() {
    // The bind group each kernel gets (its `binds`) has exactly the bindings its composed module
    // declares, each storage buffer writable exactly where the module may store to it.
    for kernel in SolveKernel::ALL {
        for energies in section_variants() {
            let module = kernel.compose(energies).validate(kernel.file()).unwrap();
            let mut declared: Vec<(u32, Option<bool>)> = module
                .global_variables
                .iter()
                .filter_map(|(_, var)| {
                    let binding = var.binding.as_ref()?;
                    assert_eq!(binding.group, 0, "{}", kernel.file());
                    let writable = match var.space {
                        naga::AddressSpace::Storage { access } => {
                            Some(access.contains(naga::StorageAccess::STORE))
                        }
                        _ => None,
                    };
                    Some((binding.binding, writable))
                })
                .collect();
            declared.sort();
            let binds: Vec<(u32, Option<bool>)> = kernel
                .binds(energies)
                .iter()
                .map(|&(r, w)| (r.binding(), r.is_storage().then_some(w)))
                .collect();
            assert_eq!(declared, binds, "{} ({energies:?})", kernel.file());
        }
    }
}

fn wgsl_struct(name: &str) -> (u32, Vec<(String, u32)>) {
    // solve.wgsl as a kernel composes it (its control binding resolved).
    let source = SolveKernel::PcgStart.compose(VbdEnergies::ALL[0]).source;
    let module = validate_wgsl("solve.wgsl", &source).expect("solve.wgsl validates");
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let fields = (members.iter())
                    .map(|m| (m.name.clone().unwrap(), m.offset))
                    .collect();
                return (*span, fields);
            }
        }
    }
    panic!("struct {name} not found in solve.wgsl");
}

fn check_layout(name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (span, fields) = wgsl_struct(name);
    assert_eq!(span as usize, size, "{name}: size");
    let got: Vec<(&str, usize)> = fields.iter().map(|(n, o)| (n.as_str(), *o as usize)).collect();
    assert_eq!(got, offsets, "{name}: fields");
}

#[test]
fn solve_structs_match_their_rust_mirrors() {
    check_layout(
        "OpParams",
        size_of::<OpParams>(),
        &[
            ("level", offset_of!(OpParams, level)),
            ("first", offset_of!(OpParams, first)),
            ("count", offset_of!(OpParams, count)),
            ("slot", offset_of!(OpParams, slot)),
            ("flag", offset_of!(OpParams, flag)),
            ("_pad0", offset_of!(OpParams, _pad0)),
            ("_pad1", offset_of!(OpParams, _pad1)),
            ("_pad2", offset_of!(OpParams, _pad2)),
        ],
    );
    check_layout(
        "SolveControl",
        size_of::<SolveControl>(),
        &[
            ("done", offset_of!(SolveControl, done)),
            ("_pad0", offset_of!(SolveControl, _pad0)),
            ("residual_max", offset_of!(SolveControl, residual_max)),
            ("residual_rms", offset_of!(SolveControl, residual_rms)),
        ],
    );
    check_layout(
        "SolveScalars",
        size_of::<SolveScalars>(),
        &[
            ("rz", offset_of!(SolveScalars, rz)),
            ("alpha", offset_of!(SolveScalars, alpha)),
            ("line_alpha", offset_of!(SolveScalars, line_alpha)),
        ],
    );
}
