//! The animated glTF binary (`.glb`): the cloth's first exported frame as the base mesh (one
//! primitive and material per panel, sharing the vertices), one morph target per later frame
//! (position and normal deltas), a weights animation that moves through them, and each body as
//! a further node over one mesh, posed or moved rigidly by its own channels.

use super::obj::unit_normals;
use crate::glb::{node, GlbDoc};
use crate::preview::BODY;
use animation::Property::{MorphTargetWeights as Weights, Rotation, Translation};
use glam::{Quat, Vec2, Vec3, Vec4};
use gltf_json as json;
use json::validation::Checked::Valid;
use json::{accessor, animation, buffer, material, mesh, Index};
use std::collections::BTreeMap;

/// The cloth over time.
#[derive(Clone, Copy, Debug)]
pub struct ClothTrack<'a> {
    /// Triangles over the vertices.
    pub triangles: &'a [[u32; 3]],
    /// Pattern coordinates in m, for pattern scenes.
    pub uv: Option<&'a [Vec2]>,
    /// Each frame's time in s, increasing.
    pub times: &'a [f32],
    /// Each frame's positions in m (world).
    pub frames: &'a [Vec<Vec3>],
    /// The materials, one per panel (one for a cloth without panels).
    pub materials: &'a [ClothMaterial],
    /// Each triangle's material (`None`: all the first).
    pub triangle_material: Option<&'a [u32]>,
    /// An image of the fabric laid over the pattern coordinates, every material's base colour.
    pub texture: Option<&'a FabricImage>,
}

/// A panel's material.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothMaterial {
    /// The panel's name.
    pub name: String,
    /// Its colour, linear RGB.
    pub color: Vec3,
}

/// A fabric image: the PNG file's bytes, and the physical size one copy covers.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricImage {
    /// The PNG file, as read.
    pub png: Vec<u8>,
    /// Width and height of one copy on the fabric, in m.
    pub size_m: [f32; 2],
}

/// A body: its mesh in its own frame and its rigid pose at each of the cloth's times (one pose
/// when it never moves).
#[derive(Clone, Debug)]
pub struct BodyTrack<'a> {
    /// The node's name (`body`, or `body0`, `body1`, … among several).
    pub name: String,
    /// Positions in the body frame, m.
    pub positions: &'a [Vec3],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// Rotation and translation, body to world.
    pub poses: Vec<(Quat, Vec3)>,
    /// A deforming body's world positions at each of the times (empty for a rigid body): its
    /// mesh then takes the first as its base and one morph target per later time, like the
    /// cloth's.
    pub frames: Vec<Vec<Vec3>>,
}

/// The `.glb` bytes of the cloth (if any) and the bodies over `times`, or `None` without
/// times, with frames of unequal length or times that do not match them, or past the format's
/// 4 GiB.
pub fn glb_bytes(
    cloth: Option<&ClothTrack>,
    bodies: &[BodyTrack],
    times: &[f32],
) -> Option<Vec<u8>> {
    if times.is_empty() {
        return None;
    }
    let mut b = Builder::default();
    b.doc.root.asset.generator = Some(format!("drapekit {}", env!("CARGO_PKG_VERSION")));
    let mut nodes = Vec::new();
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    if let Some(cloth) = cloth {
        let n = cloth.frames.first()?.len();
        if cloth.times != times || cloth.frames.iter().any(|f| f.len() != n) {
            return None;
        }
        let garment = b.cloth_mesh(cloth)?;
        nodes.push(b.doc.root.push(json::Node {
            mesh: Some(garment),
            name: Some("garment".into()),
            ..node()
        }));
        b.cloth_weights(cloth, nodes[0], &mut channels, &mut samplers);
    }
    for body in bodies {
        let (rotation, translation) = *body.poses.first()?;
        if !body.frames.is_empty()
            && (body.frames.len() != times.len()
                || body.frames.iter().any(|f| f.len() != body.positions.len()))
        {
            return None;
        }
        let mesh = b.body_mesh(body);
        let node = b.doc.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(body.name.clone()),
            rotation: Some(json::scene::UnitQuaternion(rotation.to_array())),
            translation: Some(translation.to_array()),
            ..node()
        });
        nodes.push(node);
        if body.frames.len() > 1 {
            b.weights_channel(times, body.frames.len(), node, &mut channels, &mut samplers);
        }
        if body.poses.len() > 1 {
            if body.poses.len() != times.len() {
                return None;
            }
            // glTF slerps between neighbouring keys: keep each quaternion on the same side as
            // the previous one so that the turn takes the short way, as the simulation's did.
            let mut rotations: Vec<Quat> = body.poses.iter().map(|p| p.0).collect();
            for k in 1..rotations.len() {
                if rotations[k].dot(rotations[k - 1]) < 0.0 {
                    rotations[k] = -rotations[k];
                }
            }
            let input = b.scalars(times, true);
            let flat: Vec<f32> = rotations.iter().flat_map(|q| q.to_array()).collect();
            let r = b.accessor(&flat, rotations.len(), accessor::Type::Vec4, None, None);
            let t: Vec<Vec3> = body.poses.iter().map(|p| p.1).collect();
            let t = b.vec3s(&t, false, None);
            channels.push(b.channel(&mut samplers, input, r, node, Rotation));
            channels.push(b.channel(&mut samplers, input, t, node, Translation));
        }
    }
    if !channels.is_empty() {
        b.doc.root.push(json::Animation {
            channels,
            samplers,
            name: Some("drape".into()),
            extensions: None,
            extras: Default::default(),
        });
    }
    let scene = b.doc.root.push(json::Scene {
        nodes,
        name: Some("drapekit".into()),
        extensions: None,
        extras: Default::default(),
    });
    b.doc.root.scene = Some(scene);
    b.finish()
}

impl Builder {
    /// The weights animation of the cloth's morph targets.
    fn cloth_weights(
        &mut self,
        cloth: &ClothTrack,
        node: Index<json::Node>,
        channels: &mut Vec<animation::Channel>,
        samplers: &mut Vec<animation::Sampler>,
    ) {
        self.weights_channel(cloth.times, cloth.frames.len(), node, channels, samplers);
    }

    /// The weights animation of a mesh whose `frames` frames (at `times`) are its base and one
    /// morph target per later frame.
    fn weights_channel(
        &mut self,
        times: &[f32],
        frames: usize,
        node: Index<json::Node>,
        channels: &mut Vec<animation::Channel>,
        samplers: &mut Vec<animation::Sampler>,
    ) {
        let b = self;
        let later = frames - 1;
        if later == 0 {
            return;
        }
        // Frame 0 is the base (all weights 0); frame k sets target k − 1 to 1. Linear
        // interpolation between neighbours blends two frames' positions linearly. Dense weights
        // take 4·frames² bytes, less than the targets' 24·particles·frames until frames pass
        // six times the particle count.
        let mut weights = vec![0.0f32; frames * later];
        for k in 1..frames {
            weights[k * later + k - 1] = 1.0;
        }
        let input = b.scalars(times, true);
        let output = b.scalars(&weights, false);
        channels.push(b.channel(samplers, input, output, node, Weights));
    }
}

/// The document being written, with the garment's and bodies' parts on top of the shared
/// plumbing.
#[derive(Default)]
struct Builder {
    doc: GlbDoc,
}

impl Builder {
    /// The cloth mesh: base frame, normals, pattern UVs and the morph targets, shared by one
    /// primitive per material (`None` when a triangle names a material that does not exist).
    fn cloth_mesh(&mut self, cloth: &ClothTrack) -> Option<Index<json::Mesh>> {
        let base = &cloth.frames[0];
        let base_normals = unit_normals(base, cloth.triangles);
        let mut attributes = BTreeMap::new();
        let vertex = Some(buffer::Target::ArrayBuffer);
        let positions = self.vec3s(base, true, vertex);
        let normals = self.vec3s(&base_normals, false, vertex);
        attributes.insert(Valid(mesh::Semantic::Positions), positions);
        attributes.insert(Valid(mesh::Semantic::Normals), normals);
        if let Some(uv) = cloth.uv.filter(|uv| uv.len() == base.len()) {
            let flat: Vec<f32> = match cloth.texture {
                // In copies of the image, its top row towards the panel's +y (glTF's t grows
                // down the image).
                Some(t) => (uv.iter())
                    .flat_map(|p| [p.x / t.size_m[0], -p.y / t.size_m[1]])
                    .collect(),
                // In m. glTF's texture origin is the top left, OBJ's the bottom left:
                // v' = 1 − v keeps an image where the OBJ's vt put it.
                None => uv.iter().flat_map(|t| [t.x, 1.0 - t.y]).collect(),
            };
            let uv = self.accessor(&flat, uv.len(), accessor::Type::Vec2, None, vertex);
            attributes.insert(Valid(mesh::Semantic::TexCoords(0)), uv);
        }
        let targets: Vec<mesh::MorphTarget> = (cloth.frames[1..].iter())
            .map(|frame| {
                let dp: Vec<Vec3> = frame.iter().zip(base).map(|(p, q)| *p - *q).collect();
                let dn: Vec<Vec3> = (unit_normals(frame, cloth.triangles).iter())
                    .zip(&base_normals)
                    .map(|(n, m)| *n - *m)
                    .collect();
                mesh::MorphTarget {
                    positions: Some(self.vec3s(&dp, true, vertex)),
                    normals: Some(self.vec3s(&dn, false, vertex)),
                    tangents: None,
                }
            })
            .collect();
        let texture = cloth.texture.map(|t| self.texture(&t.png));
        let mut by_material = vec![Vec::new(); cloth.materials.len()];
        for (k, t) in cloth.triangles.iter().enumerate() {
            let m = cloth.triangle_material.map_or(0, |m| m[k]) as usize;
            by_material.get_mut(m)?.push(*t);
        }
        let mut primitives = Vec::new();
        for (m, triangles) in cloth.materials.iter().zip(&by_material) {
            if triangles.is_empty() {
                continue;
            }
            // A texture carries the colour; the factor multiplies it.
            let color = if texture.is_some() {
                Vec3::ONE
            } else {
                m.color
            };
            let material = self.material(&m.name, color.extend(1.0), true, texture);
            let indices = self.indices(triangles);
            primitives.push(primitive(
                attributes.clone(),
                indices,
                material,
                targets.clone(),
            ));
        }
        let count = targets.len();
        Some(self.doc.root.push(json::Mesh {
            name: Some("garment".into()),
            primitives,
            weights: (count > 0).then(|| vec![0.0; count]),
            extensions: None,
            extras: Default::default(),
        }))
    }

    /// The fabric image as an embedded PNG, repeated over the texture coordinates.
    fn texture(&mut self, png: &[u8]) -> Index<json::Texture> {
        let view = self.view(png, None);
        let image = self.doc.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some("fabric".into()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        use json::texture::{MagFilter, MinFilter, WrappingMode};
        let sampler = self.doc.root.push(json::texture::Sampler {
            mag_filter: Some(Valid(MagFilter::Linear)),
            min_filter: Some(Valid(MinFilter::LinearMipmapLinear)),
            name: None,
            wrap_s: Valid(WrappingMode::Repeat),
            wrap_t: Valid(WrappingMode::Repeat),
            extensions: None,
            extras: Default::default(),
        });
        self.doc.root.push(json::Texture {
            name: Some("fabric".into()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: Default::default(),
        })
    }

    /// The body mesh in its own frame (a deforming body's: its first frame, and a morph target
    /// per later frame).
    fn body_mesh(&mut self, body: &BodyTrack) -> Index<json::Mesh> {
        let mut attributes = BTreeMap::new();
        let target = Some(buffer::Target::ArrayBuffer);
        let base = body.frames.first().map_or(body.positions, |f| &f[..]);
        let positions = self.vec3s(base, true, target);
        let base_normals = unit_normals(base, body.triangles);
        let normals = self.vec3s(&base_normals, false, target);
        attributes.insert(Valid(mesh::Semantic::Positions), positions);
        attributes.insert(Valid(mesh::Semantic::Normals), normals);
        let targets: Vec<mesh::MorphTarget> = (body.frames.iter().skip(1))
            .map(|frame| {
                let dp: Vec<Vec3> = frame.iter().zip(base).map(|(p, q)| *p - *q).collect();
                let dn: Vec<Vec3> = (unit_normals(frame, body.triangles).iter())
                    .zip(&base_normals)
                    .map(|(n, m)| *n - *m)
                    .collect();
                mesh::MorphTarget {
                    positions: Some(self.vec3s(&dp, true, target)),
                    normals: Some(self.vec3s(&dn, false, target)),
                    tangents: None,
                }
            })
            .collect();
        let count = targets.len();
        let material = self.material("body", BODY.extend(1.0), false, None);
        let indices = self.indices(body.triangles);
        self.doc.root.push(json::Mesh {
            name: Some(body.name.clone()),
            primitives: vec![primitive(attributes, indices, material, targets)],
            weights: (count > 0).then(|| vec![0.0; count]),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// A matte material, optionally with a base-colour texture; cloth is seen from both sides.
    fn material(
        &mut self,
        name: &str,
        color: Vec4,
        two_sided: bool,
        texture: Option<Index<json::Texture>>,
    ) -> Index<json::Material> {
        let mut m = json::Material {
            name: Some(name.into()),
            double_sided: two_sided,
            ..Default::default()
        };
        m.pbr_metallic_roughness.base_color_factor = material::PbrBaseColorFactor(color.to_array());
        m.pbr_metallic_roughness.base_color_texture = texture.map(|index| json::texture::Info {
            index,
            tex_coord: 0,
            extensions: None,
            extras: Default::default(),
        });
        m.pbr_metallic_roughness.metallic_factor = material::StrengthFactor(0.0);
        m.pbr_metallic_roughness.roughness_factor = material::StrengthFactor(0.9);
        self.doc.root.push(m)
    }

    /// Appends `bytes` (little endian, as glTF requires) as a buffer view, 4-byte aligned
    /// (every component here is 4 bytes).
    fn view(&mut self, bytes: &[u8], target: Option<buffer::Target>) -> Index<buffer::View> {
        self.doc.view(bytes, target)
    }

    /// An f32 accessor of `count` elements of `kind`.
    fn accessor(
        &mut self,
        values: &[f32],
        count: usize,
        kind: accessor::Type,
        bounds: Option<(json::Value, json::Value)>,
        target: Option<buffer::Target>,
    ) -> Index<json::Accessor> {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let f32s = accessor::ComponentType::F32;
        (self.doc).accessor(&bytes, count, kind, f32s, bounds, target)
    }

    /// Vec3 data; `bounds` adds the min/max that glTF requires of positions.
    fn vec3s(
        &mut self,
        v: &[Vec3],
        bounds: bool,
        target: Option<buffer::Target>,
    ) -> Index<json::Accessor> {
        let bounds = bounds.then(|| {
            let lo = v.iter().copied().reduce(Vec3::min).unwrap_or_default();
            let hi = v.iter().copied().reduce(Vec3::max).unwrap_or_default();
            (
                json::Value::from(lo.to_array().to_vec()),
                hi.to_array().to_vec().into(),
            )
        });
        let flat: Vec<f32> = v.iter().flat_map(|p| p.to_array()).collect();
        self.accessor(&flat, v.len(), accessor::Type::Vec3, bounds, target)
    }

    /// Scalars; `bounds` adds the min/max that glTF requires of animation times.
    fn scalars(&mut self, v: &[f32], bounds: bool) -> Index<json::Accessor> {
        let bounds = bounds.then(|| {
            let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (vec![lo].into(), vec![hi].into())
        });
        self.accessor(v, v.len(), accessor::Type::Scalar, bounds, None)
    }

    /// Triangle indices as u32.
    fn indices(&mut self, triangles: &[[u32; 3]]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let (count, u32s) = (3 * triangles.len(), accessor::ComponentType::U32);
        let target = Some(buffer::Target::ElementArrayBuffer);
        (self.doc).accessor(&bytes, count, accessor::Type::Scalar, u32s, None, target)
    }

    /// A linear sampler from `input` times to `output` values, driving `path` of `node`.
    fn channel(
        &mut self,
        samplers: &mut Vec<animation::Sampler>,
        input: Index<json::Accessor>,
        output: Index<json::Accessor>,
        node: Index<json::Node>,
        path: animation::Property,
    ) -> animation::Channel {
        samplers.push(animation::Sampler {
            input,
            interpolation: Valid(animation::Interpolation::Linear),
            output,
            extensions: None,
            extras: Default::default(),
        });
        animation::Channel {
            sampler: Index::new(samplers.len() as u32 - 1),
            target: animation::Target {
                node,
                path: Valid(path),
                extensions: None,
                extras: Default::default(),
            },
            extensions: None,
            extras: Default::default(),
        }
    }

    /// The GLB bytes (`None` past the format's 32-bit sizes).
    fn finish(self) -> Option<Vec<u8>> {
        self.doc.finish()
    }
}

/// A triangle-list primitive.
fn primitive(
    attributes: BTreeMap<json::validation::Checked<mesh::Semantic>, Index<json::Accessor>>,
    indices: Index<json::Accessor>,
    material: Index<json::Material>,
    targets: Vec<mesh::MorphTarget>,
) -> mesh::Primitive {
    mesh::Primitive {
        attributes,
        indices: Some(indices),
        material: Some(material),
        mode: Valid(mesh::Mode::Triangles),
        targets: (!targets.is_empty()).then_some(targets),
        extensions: None,
        extras: Default::default(),
    }
}
