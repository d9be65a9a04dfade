//! The element arrays each GPU stage binds (springs, hinges, seams, triangles, self-collision
//! neighbours, the bodies' SDF nodes), in binding order, and their texel contents.

use super::array_layout::ArrayLayout;
use super::kernels::VbdEnergies;
use crate::model::ClothModel;
use crate::plan::Pass;
use wgpu::TextureFormat::{R32Float, R32Uint, Rgba32Uint};

/// Which element arrays a stage binds, in binding order.
#[derive(Clone, Copy)]
pub(super) enum Elements {
    Springs,
    /// The spring arrays with no spring in them (implicit Euler's solve of a membrane, whose
    /// springs carry no force).
    NoSprings,
    Hinges,
    /// Hinge offsets (their total counts the hinges), the hinges and their slots (for
    /// `hinge_forces`).
    HingeSlots,
    /// Hinge offsets (for `integrate`'s gather).
    HingeOffsets,
    Seams,
    Membranes,
    Triangles,
    SelfNeighbours,
    Sdf,
}

impl Elements {
    /// Where this kind's arrays live under the context's `layout`. The bodies' signed distance
    /// field stays a texture: its sampling helpers take the grid as a function argument, which
    /// WGSL allows for textures and not for storage arrays.
    pub(super) fn layout(self, layout: ArrayLayout) -> ArrayLayout {
        match self {
            Elements::Sdf => ArrayLayout::Textures,
            _ => layout,
        }
    }
}

pub(super) fn stage_elements(pass: Pass, energies: VbdEnergies) -> Vec<Elements> {
    match pass {
        Pass::SpringForces | Pass::StrainLimit | Pass::Monitor => vec![Elements::Springs],
        Pass::HingeForces => vec![Elements::HingeSlots],
        Pass::BendingForces => vec![Elements::Hinges],
        Pass::WindForces => vec![Elements::Triangles],
        Pass::SeamForces => vec![Elements::Seams],
        Pass::MembraneForces => vec![Elements::Membranes],
        Pass::SelfCollide => vec![Elements::SelfNeighbours],
        Pass::CollideBody => vec![Elements::Sdf],
        Pass::VbdSolve => {
            let mut kinds = vec![Elements::Springs];
            if energies.bending {
                kinds.push(Elements::Hinges);
            }
            if energies.seams {
                kinds.push(Elements::Seams);
            }
            if energies.body {
                kinds.push(Elements::Sdf);
            }
            kinds
        }
        // `integrate` gathers the bending forces when the plan evaluates hinges.
        Pass::Integrate if energies.bending => vec![Elements::HingeOffsets],
        Pass::HashClear
        | Pass::HashCount
        | Pass::HashScan
        | Pass::HashFill
        | Pass::VbdInit
        | Pass::VbdFinish
        | Pass::Integrate => vec![],
    }
}

/// Where each hinge's four forces go on the GPU: the CSR slots of its refs, `[u32; 4]` per
/// hinge. `hinge_forces` scatters to them and `integrate` then reads each particle's bending
/// forces as one contiguous run of texels, in CSR order (the CPU twin keeps the forces in ref
/// order, `4·h + role`, and gathers through the refs: the same numbers, the same sum order).
fn hinge_slots(refs: &[u32]) -> Vec<u32> {
    let mut slots = vec![0u32; refs.len()];
    for (k, &r) in refs.iter().enumerate() {
        slots[r as usize] = k as u32;
    }
    slots
}

/// The texel arrays of one kind of element: (label, texel format, bytes).
pub(super) fn element_arrays(
    model: &ClothModel,
    kind: Elements,
) -> Vec<(&'static str, wgpu::TextureFormat, Vec<u8>)> {
    let bytes = |data: &[u8]| data.to_vec();
    match kind {
        Elements::Springs | Elements::SelfNeighbours => {
            let csr = model.spring_csr();
            let (offsets, items) = match kind {
                Elements::Springs => ("spring_offsets", "springs"),
                _ => ("self_neighbour_offsets", "self_neighbours"),
            };
            vec![
                (offsets, R32Uint, bytes(bytemuck::cast_slice(&csr.offsets))),
                (items, Rgba32Uint, bytes(bytemuck::cast_slice(&csr.items))),
            ]
        }
        Elements::NoSprings => {
            let offsets = vec![0u32; model.len() + 1];
            vec![
                (
                    "spring_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&offsets)),
                ),
                ("springs", Rgba32Uint, Vec::new()),
            ]
        }
        Elements::HingeSlots => {
            let csr = model.hinge_csr();
            vec![
                (
                    "hinge_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.offsets)),
                ),
                (
                    "hinges",
                    Rgba32Uint,
                    bytes(bytemuck::cast_slice(&model.hinges)),
                ),
                (
                    "hinge_slots",
                    Rgba32Uint,
                    bytes(bytemuck::cast_slice(&hinge_slots(&csr.items))),
                ),
            ]
        }
        Elements::HingeOffsets => {
            let csr = model.hinge_csr();
            vec![(
                "hinge_offsets",
                R32Uint,
                bytes(bytemuck::cast_slice(&csr.offsets)),
            )]
        }
        Elements::Hinges => {
            let csr = model.hinge_csr();
            vec![
                (
                    "hinge_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.offsets)),
                ),
                (
                    "hinge_refs",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.items)),
                ),
                (
                    "hinges",
                    Rgba32Uint,
                    bytes(bytemuck::cast_slice(&model.hinges)),
                ),
            ]
        }
        Elements::Seams => {
            let csr = model.seam_csr();
            vec![
                (
                    "seam_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.offsets)),
                ),
                (
                    "seam_refs",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.items)),
                ),
                (
                    "seams",
                    Rgba32Uint,
                    bytes(bytemuck::cast_slice(&model.seams)),
                ),
            ]
        }
        Elements::Membranes => {
            let csr = model.membrane_csr();
            vec![
                (
                    "membrane_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.offsets)),
                ),
                (
                    "membrane_refs",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.items)),
                ),
                (
                    "membranes",
                    Rgba32Uint,
                    bytes(bytemuck::cast_slice(&model.membranes)),
                ),
            ]
        }
        Elements::Triangles => {
            let csr = model.triangle_csr();
            let tris = model.packed_triangles();
            vec![
                (
                    "triangle_offsets",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.offsets)),
                ),
                (
                    "triangle_refs",
                    R32Uint,
                    bytes(bytemuck::cast_slice(&csr.items)),
                ),
                ("triangles", Rgba32Uint, bytes(bytemuck::cast_slice(&tris))),
            ]
        }
        Elements::Sdf => {
            // Every body's nodes one after another, as `BodyParams::sdf_dims.w` counts them.
            let nodes: Vec<f32> = (model.colliders.iter())
                .flat_map(|c| c.sdf.values.iter().copied())
                .collect();
            vec![("sdf", R32Float, bytes(bytemuck::cast_slice(&nodes)))]
        }
    }
}
