//! The Rust mirrors in src/model/layout.rs match kernels/common.wgsl byte for byte: sizes and
//! every field offset, as naga lays the WGSL structs out.

use drapekit::gpu::kernels::{validate_wgsl, COMMON_WGSL};
use drapekit::model::layout::{
    BodyParams, BodyPose, Hinge, Membrane, Seam, SimParams, SpringRef, SubstepParams, Sweep,
};
use std::mem::{offset_of, size_of};

fn wgsl_layout(name: &str) -> (u32, Vec<(String, u32)>) {
    let module = validate_wgsl("common.wgsl", COMMON_WGSL).expect("common.wgsl validates");
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let fields = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap(), m.offset))
                    .collect();
                return (*span, fields);
            }
        }
    }
    panic!("struct {name} not found in common.wgsl");
}

fn check(name: &str, rust_size: usize, rust_offsets: &[(&str, usize)]) {
    let (span, fields) = wgsl_layout(name);
    assert_eq!(span as usize, rust_size, "{name}: size");
    assert_eq!(fields.len(), rust_offsets.len(), "{name}: field count");
    for ((wname, woff), (rname, roff)) in fields.iter().zip(rust_offsets) {
        assert_eq!(wname, rname, "{name}: field order");
        assert_eq!(*woff as usize, *roff, "{name}.{wname}: offset");
    }
}

#[test]
fn sim_params_layout() {
    check(
        "SimParams",
        size_of::<SimParams>(),
        &[
            ("gravity", offset_of!(SimParams, gravity)),
            ("num_particles", offset_of!(SimParams, num_particles)),
            ("integrator", offset_of!(SimParams, integrator)),
            ("dt", offset_of!(SimParams, dt)),
            ("air_damping", offset_of!(SimParams, air_damping)),
            ("air_density", offset_of!(SimParams, air_density)),
            ("drag_coefficient", offset_of!(SimParams, drag_coefficient)),
            ("sewing_rate", offset_of!(SimParams, sewing_rate)),
            ("iterations", offset_of!(SimParams, iterations)),
            ("self_thickness", offset_of!(SimParams, self_thickness)),
            ("hash_cell", offset_of!(SimParams, hash_cell)),
            ("hash_buckets", offset_of!(SimParams, hash_buckets)),
            ("strain_limit", offset_of!(SimParams, strain_limit)),
            (
                "strain_iterations",
                offset_of!(SimParams, strain_iterations),
            ),
            ("tolerance", offset_of!(SimParams, tolerance)),
            ("num_bodies", offset_of!(SimParams, num_bodies)),
            ("smoothing", offset_of!(SimParams, smoothing)),
            ("euler_onset", offset_of!(SimParams, euler_onset)),
            ("membrane_onset", offset_of!(SimParams, membrane_onset)),
            ("buckled_fraction", offset_of!(SimParams, buckled_fraction)),
            ("_pad0", offset_of!(SimParams, _pad0)),
            ("stiffening", offset_of!(SimParams, stiffening)),
            ("bodies", offset_of!(SimParams, bodies)),
        ],
    );
}

#[test]
fn body_params_layout() {
    check(
        "BodyParams",
        size_of::<BodyParams>(),
        &[
            ("sdf_origin", offset_of!(BodyParams, sdf_origin)),
            ("sdf_dims", offset_of!(BodyParams, sdf_dims)),
            ("thickness", offset_of!(BodyParams, thickness)),
            ("friction", offset_of!(BodyParams, friction)),
            ("normal_loss", offset_of!(BodyParams, normal_loss)),
            ("tangential_loss", offset_of!(BodyParams, tangential_loss)),
            (
                "friction_slip_speed",
                offset_of!(BodyParams, friction_slip_speed),
            ),
            ("parts", offset_of!(BodyParams, parts)),
            ("first_part", offset_of!(BodyParams, first_part)),
            ("_pad2", offset_of!(BodyParams, _pad2)),
        ],
    );
}

#[test]
fn body_pose_layout() {
    check(
        "BodyPose",
        size_of::<BodyPose>(),
        &[
            ("x", offset_of!(BodyPose, x)),
            ("y", offset_of!(BodyPose, y)),
            ("z", offset_of!(BodyPose, z)),
            ("translation", offset_of!(BodyPose, translation)),
            ("velocity", offset_of!(BodyPose, velocity)),
            ("angular_velocity", offset_of!(BodyPose, angular_velocity)),
        ],
    );
}

#[test]
fn substep_params_layout() {
    check(
        "SubstepParams",
        size_of::<SubstepParams>(),
        &[
            ("wind", offset_of!(SubstepParams, wind)),
            ("time", offset_of!(SubstepParams, time)),
            ("substep", offset_of!(SubstepParams, substep)),
            ("_pad0", offset_of!(SubstepParams, _pad0)),
            ("_pad1", offset_of!(SubstepParams, _pad1)),
            ("bodies", offset_of!(SubstepParams, bodies)),
            ("parts", offset_of!(SubstepParams, parts)),
        ],
    );
}

#[test]
fn spring_ref_layout() {
    check(
        "SpringRef",
        size_of::<SpringRef>(),
        &[
            ("other", offset_of!(SpringRef, other)),
            ("rest_length", offset_of!(SpringRef, rest_length)),
            ("stiffness", offset_of!(SpringRef, stiffness)),
            ("damping", offset_of!(SpringRef, damping)),
        ],
    );
}

#[test]
fn seam_layout() {
    check(
        "Seam",
        size_of::<Seam>(),
        &[
            ("v", offset_of!(Seam, v)),
            ("weight", offset_of!(Seam, weight)),
            ("stiffness", offset_of!(Seam, stiffness)),
            ("damping", offset_of!(Seam, damping)),
            ("open_gap", offset_of!(Seam, open_gap)),
        ],
    );
}

#[test]
fn hinge_layout() {
    check(
        "Hinge",
        size_of::<Hinge>(),
        &[
            ("v", offset_of!(Hinge, v)),
            ("stiffness", offset_of!(Hinge, stiffness)),
            ("rest_sin_half", offset_of!(Hinge, rest_sin_half)),
            ("rest_weight", offset_of!(Hinge, rest_weight)),
            ("_pad1", offset_of!(Hinge, _pad1)),
        ],
    );
}

#[test]
fn membrane_layout() {
    check(
        "Membrane",
        size_of::<Membrane>(),
        &[
            ("v", offset_of!(Membrane, v)),
            ("shape", offset_of!(Membrane, shape)),
            ("stiffness", offset_of!(Membrane, stiffness)),
        ],
    );
}

#[test]
fn sweep_layout() {
    check(
        "Sweep",
        size_of::<Sweep>(),
        &[
            ("first", offset_of!(Sweep, first)),
            ("count", offset_of!(Sweep, count)),
            ("iteration", offset_of!(Sweep, iteration)),
            ("_pad0", offset_of!(Sweep, _pad0)),
        ],
    );
}

/// A constant of common.wgsl, as naga evaluates it.
fn wgsl_literal(name: &str) -> naga::Literal {
    let module = validate_wgsl("common.wgsl", COMMON_WGSL).expect("common.wgsl validates");
    for (_, c) in module.constants.iter() {
        if c.name.as_deref() == Some(name) {
            if let naga::Expression::Literal(v) = module.global_expressions[c.init] {
                return v;
            }
        }
    }
    panic!("constant {name} not found in common.wgsl");
}

/// A `u32` constant of common.wgsl.
fn wgsl_const(name: &str) -> u32 {
    match wgsl_literal(name) {
        naga::Literal::U32(v) => v,
        other => panic!("{name} is {other:?}, not a u32"),
    }
}

#[test]
fn shared_constants_match() {
    use drapekit::model::layout::{MAX_BODIES, TEXELS_PER_ROW, WORKGROUP_SIZE};
    assert_eq!(wgsl_const("MAX_BODIES") as usize, MAX_BODIES);
    assert_eq!(wgsl_const("TEXELS_PER_ROW"), TEXELS_PER_ROW);
    assert_eq!(wgsl_const("WORKGROUP_SIZE"), WORKGROUP_SIZE);
    assert_eq!(
        wgsl_literal("VBD_STEP_FLOOR"),
        naga::Literal::F32(drapekit::model::layout::VBD_STEP_FLOOR)
    );
    // Texture rows are copied to and from buffers, which needs 256-byte aligned rows.
    assert_eq!((TEXELS_PER_ROW * 4) % 256, 0, "r32uint rows");
}

#[test]
fn structs_stored_in_texels_fill_whole_texels() {
    // unpack_spring and unpack_hinge read one and two rgba32uint texels (16 bytes each).
    assert_eq!(size_of::<SpringRef>(), 16);
    assert_eq!(size_of::<Hinge>(), 32);
    assert_eq!(size_of::<Seam>(), 32);
    // A membrane is three texels.
    assert_eq!(size_of::<Membrane>(), 48);
}
