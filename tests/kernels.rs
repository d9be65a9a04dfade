//! Every kernel, composed with common.wgsl, validates with naga and builds a pipeline.

mod common;

use drapekit::gpu::implicit::{Include, SolveKernel};
use drapekit::gpu::kernels::{
    compose, compose_with, validate_wgsl, ForceInput, VbdEnergies, COMMON_WGSL,
};
use drapekit::plan::Pass;

#[test]
fn naga_validates_every_kernel() {
    // Force stages come in two variants: first of the substep, or reading the previous sum.
    for pass in Pass::ALL {
        for input in ForceInput::ALL {
            let label = format!("kernels/{}.wgsl ({input:?})", pass.name());
            if let Err(report) = validate_wgsl(&label, &compose(pass, input)) {
                panic!("{report}");
            }
        }
    }
}

#[test]
fn naga_validates_every_kernel_without_its_optional_sections() {
    // Sections left out (a scene without bending, seams or a body) must still compose.
    for pass in Pass::ALL {
        for energies in VbdEnergies::ALL {
            let label = format!("kernels/{}.wgsl ({energies:?})", pass.name());
            let source = compose_with(pass, ForceInput::Zero, energies);
            if let Err(report) = validate_wgsl(&label, &source) {
                panic!("{report}");
            }
        }
    }
}

#[test]
fn every_kernel_file_is_a_pass_or_a_solve_kernel() {
    // A kernel file that no Pass, solve kernel or composition names would never be validated or
    // run (the solve's kernels are validated in tests/implicit_gpu.rs).
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("kernels");
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let stem = name.trim_end_matches(".wgsl");
        assert!(
            ["common", "solve"].contains(&stem)
                || Pass::ALL.iter().any(|p| p.name() == stem)
                || SolveKernel::ALL.iter().any(|k| k.file() == stem)
                || Include::ALL.iter().any(|i| i.file() == stem),
            "kernels/{name} is not a Pass, a solve kernel or an include"
        );
    }
}

#[test]
fn validation_errors_point_at_the_line() {
    let broken = format!("{COMMON_WGSL}\nfn main() {{ let x: f32 = 1u; }}\n");
    let report = validate_wgsl("broken.wgsl", &broken).unwrap_err();
    let line = COMMON_WGSL.lines().count() + 2;
    assert!(report.contains(&format!("broken.wgsl:{line}")), "{report}");
}
