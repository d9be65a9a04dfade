//! Writing a skinned body as glTF 2.0 binary (`.glb`): the mesh in its rest pose with four
//! joints and weights per vertex, the joints as a node hierarchy with their inverse bind
//! matrices, and each clip as an animation. `gltf_read` reads it back: drapekit's own rigged
//! mannequin takes the same path as an avatar exported from Blender.

use super::skin::{Interpolation, SkinnedMesh, Values};
use crate::glb::{node, GlbDoc};
use gltf_json as json;
use json::validation::Checked::Valid;
use json::{accessor, animation, buffer, mesh, Index};
use std::collections::BTreeMap;

/// The `.glb` bytes of `body` (`None` past the format's 32-bit sizes).
pub fn skinned_glb(body: &SkinnedMesh, name: &str) -> Option<Vec<u8>> {
    let mut b = Builder::default();
    b.doc.root.asset.generator = Some(format!("drapekit {}", env!("CARGO_PKG_VERSION")));
    let s = &body.skeleton;
    // Joint nodes first (node j is joint j), then the mesh node.
    for (j, local) in s.rest.iter().enumerate() {
        let children: Vec<Index<json::Node>> = (s.parents.iter().enumerate())
            .filter(|(_, p)| **p == Some(j))
            .map(|(c, _)| Index::new(c as u32))
            .collect();
        b.doc.root.push(json::Node {
            name: Some(s.names[j].clone()),
            translation: Some(local.translation.to_array()),
            rotation: Some(json::scene::UnitQuaternion(local.rotation.to_array())),
            scale: (local.scale != glam::Vec3::ONE).then(|| local.scale.to_array()),
            children: (!children.is_empty()).then_some(children),
            ..node()
        });
    }
    let ibm: Vec<f32> = s
        .inverse_bind
        .iter()
        .flat_map(|m| m.to_cols_array())
        .collect();
    let ibm = b.floats(&ibm, s.len(), accessor::Type::Mat4, None);
    let skin = b.doc.root.push(json::Skin {
        inverse_bind_matrices: Some(ibm),
        joints: (0..s.len() as u32).map(Index::new).collect(),
        skeleton: None,
        name: Some(format!("{name} skeleton")),
        extensions: None,
        extras: Default::default(),
    });
    let mesh = b.mesh(body, name);
    let mesh_node = b.doc.root.push(json::Node {
        name: Some(name.into()),
        mesh: Some(mesh),
        skin: Some(skin),
        ..node()
    });
    for clip in &body.clips {
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for c in &clip.channels {
            let input = b.floats(&c.times, c.times.len(), accessor::Type::Scalar, Some(true));
            let (output, path) = match &c.values {
                Values::Translation(v) => (b.vec3s(v), animation::Property::Translation),
                Values::Scale(v) => (b.vec3s(v), animation::Property::Scale),
                Values::Rotation(q) => {
                    let flat: Vec<f32> = q.iter().flat_map(|q| q.to_array()).collect();
                    let out = b.floats(&flat, q.len(), accessor::Type::Vec4, None);
                    (out, animation::Property::Rotation)
                }
            };
            samplers.push(animation::Sampler {
                input,
                interpolation: Valid(match c.interpolation {
                    Interpolation::Step => animation::Interpolation::Step,
                    Interpolation::Linear => animation::Interpolation::Linear,
                    Interpolation::CubicSpline => animation::Interpolation::CubicSpline,
                }),
                output,
                extensions: None,
                extras: Default::default(),
            });
            channels.push(animation::Channel {
                sampler: Index::new(samplers.len() as u32 - 1),
                target: animation::Target {
                    node: Index::new(c.joint as u32),
                    path: Valid(path),
                    extensions: None,
                    extras: Default::default(),
                },
                extensions: None,
                extras: Default::default(),
            });
        }
        b.doc.root.push(json::Animation {
            channels,
            samplers,
            name: Some(clip.name.clone()),
            extensions: None,
            extras: Default::default(),
        });
    }
    let mut nodes = vec![mesh_node];
    nodes.extend(
        (s.parents.iter().enumerate())
            .filter(|(_, p)| p.is_none())
            .map(|(j, _)| Index::new(j as u32)),
    );
    let scene = b.doc.root.push(json::Scene {
        nodes,
        name: Some(name.into()),
        extensions: None,
        extras: Default::default(),
    });
    b.doc.root.scene = Some(scene);
    b.finish()
}

/// The document being written, with this writer's parts on top of the shared plumbing.
#[derive(Default)]
struct Builder {
    doc: GlbDoc,
}

impl Builder {
    /// The skinned mesh: positions, normals, joints, weights and indices.
    fn mesh(&mut self, body: &SkinnedMesh, name: &str) -> Index<json::Mesh> {
        let m = &body.mesh;
        let vertex = Some(buffer::Target::ArrayBuffer);
        let mut attributes = BTreeMap::new();
        let positions = self.vec3s_bounded(&m.positions);
        let normals = crate::mesh::vertex_normals(&m.positions, &m.triangles);
        let normals = self.vec3s(&normals);
        let joints: Vec<u8> = (body.influences.iter())
            .flat_map(|i| i.joints)
            .flat_map(u16::to_le_bytes)
            .collect();
        let joints = self.accessor(
            &joints,
            m.positions.len(),
            accessor::Type::Vec4,
            accessor::ComponentType::U16,
            None,
            vertex,
        );
        let weights: Vec<f32> = body.influences.iter().flat_map(|i| i.weights).collect();
        let weights = self.floats(&weights, m.positions.len(), accessor::Type::Vec4, None);
        attributes.insert(Valid(mesh::Semantic::Positions), positions);
        attributes.insert(Valid(mesh::Semantic::Normals), normals);
        attributes.insert(Valid(mesh::Semantic::Joints(0)), joints);
        attributes.insert(Valid(mesh::Semantic::Weights(0)), weights);
        let indices: Vec<u8> = (m.triangles.iter().flatten())
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let indices = self.accessor(
            &indices,
            3 * m.triangles.len(),
            accessor::Type::Scalar,
            accessor::ComponentType::U32,
            None,
            Some(buffer::Target::ElementArrayBuffer),
        );
        let mut material = json::Material {
            name: Some("body".into()),
            ..Default::default()
        };
        let color = crate::body::BODY_COLOR;
        material.pbr_metallic_roughness.base_color_factor =
            json::material::PbrBaseColorFactor([color[0], color[1], color[2], 1.0]);
        material.pbr_metallic_roughness.metallic_factor = json::material::StrengthFactor(0.0);
        material.pbr_metallic_roughness.roughness_factor = json::material::StrengthFactor(0.9);
        let material = self.doc.root.push(material);
        self.doc.root.push(json::Mesh {
            name: Some(name.into()),
            primitives: vec![mesh::Primitive {
                attributes,
                indices: Some(indices),
                material: Some(material),
                mode: Valid(mesh::Mode::Triangles),
                targets: None,
                extensions: None,
                extras: Default::default(),
            }],
            weights: None,
            extensions: None,
            extras: Default::default(),
        })
    }

    /// An accessor over `bytes` (little endian), in a view of its own.
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        kind: accessor::Type,
        component: accessor::ComponentType,
        bounds: Option<(json::Value, json::Value)>,
        target: Option<buffer::Target>,
    ) -> Index<json::Accessor> {
        (self.doc).accessor(bytes, count, kind, component, bounds, target)
    }

    /// f32 data; `scalar_bounds` adds the min and max that animation times need.
    fn floats(
        &mut self,
        v: &[f32],
        count: usize,
        kind: accessor::Type,
        scalar_bounds: Option<bool>,
    ) -> Index<json::Accessor> {
        let bounds = scalar_bounds.map(|_| {
            let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (vec![lo].into(), vec![hi].into())
        });
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let component = accessor::ComponentType::F32;
        self.accessor(&bytes, count, kind, component, bounds, None)
    }

    fn vec3s(&mut self, v: &[glam::Vec3]) -> Index<json::Accessor> {
        let flat: Vec<f32> = v.iter().flat_map(|p| p.to_array()).collect();
        self.floats(&flat, v.len(), accessor::Type::Vec3, None)
    }

    /// Positions, with the bounds glTF requires of them.
    fn vec3s_bounded(&mut self, v: &[glam::Vec3]) -> Index<json::Accessor> {
        let lo = v
            .iter()
            .copied()
            .reduce(glam::Vec3::min)
            .unwrap_or_default();
        let hi = v
            .iter()
            .copied()
            .reduce(glam::Vec3::max)
            .unwrap_or_default();
        let bytes: Vec<u8> = (v.iter().flat_map(|p| p.to_array()))
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let bounds = (
            json::Value::from(lo.to_array().to_vec()),
            hi.to_array().to_vec().into(),
        );
        self.accessor(
            &bytes,
            v.len(),
            accessor::Type::Vec3,
            accessor::ComponentType::F32,
            Some(bounds),
            Some(buffer::Target::ArrayBuffer),
        )
    }

    /// The GLB bytes (`None` past the format's 32-bit sizes).
    fn finish(self) -> Option<Vec<u8>> {
        self.doc.finish()
    }
}
