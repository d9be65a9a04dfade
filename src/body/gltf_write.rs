//! Writing a skinned body as glTF 2.0 binary (`.glb`): the mesh in its rest pose with four
//! joints and weights per vertex, the joints as a node hierarchy with their inverse bind
//! matrices, and each clip as an animation. `gltf_read` reads it back: drapekit's own rigged
//! mannequin takes the same path as an avatar exported from Blender.

use super::skin::{Interpolation, SkinnedMesh, Values};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use json::{accessor, animation, buffer, mesh, Index};
use std::collections::BTreeMap;

/// The `.glb` bytes of `body` (`None` past the format's 32-bit sizes).
pub fn skinned_glb(body: &SkinnedMesh, name: &str) -> Option<Vec<u8>> {
    let mut b = Builder::default();
    b.root.asset.generator = Some(format!("drapekit {}", env!("CARGO_PKG_VERSION")));
    let s = &body.skeleton;
    // Joint nodes first (node j is joint j), then the mesh node.
    for (j, local) in s.rest.iter().enumerate() {
        let children: Vec<Index<json::Node>> = (s.parents.iter().enumerate())
            .filter(|(_, p)| **p == Some(j))
            .map(|(c, _)| Index::new(c as u32))
            .collect();
        b.root.push(json::Node {
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
    let skin = b.root.push(json::Skin {
        inverse_bind_matrices: Some(ibm),
        joints: (0..s.len() as u32).map(Index::new).collect(),
        skeleton: None,
        name: Some(format!("{name} skeleton")),
        extensions: None,
        extras: Default::default(),
    });
    let mesh = b.mesh(body, name);
    let mesh_node = b.root.push(json::Node {
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
        b.root.push(json::Animation {
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
    let scene = b.root.push(json::Scene {
        nodes,
        name: Some(name.into()),
        extensions: None,
        extras: Default::default(),
    });
    b.root.scene = Some(scene);
    b.finish()
}

fn node() -> json::Node {
    json::Node {
        camera: None,
        children: None,
        extensions: None,
        extras: Default::default(),
        matrix: None,
        mesh: None,
        name: None,
        rotation: None,
        scale: None,
        translation: None,
        skin: None,
        weights: None,
    }
}

/// The glTF document and its binary chunk, filled together.
#[derive(Default)]
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
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
        let material = self.root.push(material);
        self.root.push(json::Mesh {
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

    /// An accessor over `bytes` (little endian), in a 4-byte aligned buffer view.
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        kind: accessor::Type,
        component: accessor::ComponentType,
        bounds: Option<(json::Value, json::Value)>,
        target: Option<buffer::Target>,
    ) -> Index<json::Accessor> {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let view = self.root.push(buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        });
        let (min, max) = bounds.unzip();
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(accessor::GenericComponentType(component)),
            type_: Valid(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
            extensions: None,
            extras: Default::default(),
        })
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

    /// The GLB container: a 12-byte header, the JSON chunk (padded with spaces) and the binary
    /// chunk (padded with zeros), each 4-byte aligned.
    fn finish(mut self) -> Option<Vec<u8>> {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.root.push(json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let mut text = self.root.to_vec().ok()?;
        text.resize(text.len().next_multiple_of(4), b' ');
        let total = u32::try_from(12 + 8 + text.len() + 8 + self.bin.len()).ok()?;
        let mut out = Vec::with_capacity(total as usize);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&total.to_le_bytes());
        for (kind, chunk) in [(b"JSON", &text), (b"BIN\0", &self.bin)] {
            out.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
            out.extend_from_slice(kind);
            out.extend_from_slice(chunk);
        }
        Some(out)
    }
}
