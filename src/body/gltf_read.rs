//! Reading a skinned body from glTF 2.0 (`.glb`, or `.gltf` with its `.bin` files): the first
//! skin's mesh primitives in the rest pose, its joints, inverse bind matrices and every
//! animation's joint channels.

use super::skin::{Channel, Clip, Influence, Interpolation, Skeleton, SkinnedMesh, Trs, Values};
use crate::error::InputError;
use crate::mesh::TriMesh;
use glam::{Mat4, Quat, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::util::ReadOutputs;
use gltf::animation::Property;
use std::collections::HashMap;
use std::path::Path;

/// Reads `path` (named by scene key `key` in errors).
pub fn read_skinned(path: &Path, key: &str) -> Result<SkinnedMesh, InputError> {
    let bytes = std::fs::read(path).map_err(|e| {
        InputError::new(
            path,
            key,
            format!("cannot read the glTF file: {e}"),
            "check that the path exists (it is relative to the scene file)",
        )
    })?;
    parse_skinned(&bytes, path.parent(), path, key)
}

/// Parses glTF bytes; external buffers are read from `folder`. `name` stands for the file in
/// errors.
pub fn parse_skinned(
    bytes: &[u8],
    folder: Option<&Path>,
    name: &Path,
    key: &str,
) -> Result<SkinnedMesh, InputError> {
    let bad = |problem: String, fix: &str| InputError::new(name, key, problem, fix);
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| {
        bad(
            format!("is not a valid glTF 2.0 file: {e}"),
            "export the avatar as glTF 2.0 (.glb, or .gltf with its .bin)",
        )
    })?;
    let buffers = load_buffers(&gltf, folder, name, key)?;
    let doc = &gltf.document;
    let Some(skin) = doc.skins().next() else {
        return Err(bad(
            "has no skin: no skeleton moves its mesh".into(),
            "export the avatar with its armature (a skinned mesh), or give its motion as a \
             vertex cache (cache = \"walk.pc2\" beside an OBJ body)",
        ));
    };
    no_cycle(doc, &bad)?;
    if let Some(acc) = skin.inverse_bind_matrices() {
        readable(
            &acc,
            &[DataType::F32],
            Dimensions::Mat4,
            "inverse bind matrices",
            &bad,
        )?;
    }
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|v| &v[..]);
    // Each is the inverse of a joint's bind pose, so it must be finite and invertible itself
    // (a zero matrix skinned every vertex to NaN).
    let matrices = skin.reader(get).read_inverse_bind_matrices();
    let singular = |c: &[[f32; 4]; 4]| {
        let det = Mat4::from_cols_array_2d(c).determinant();
        !(c.iter().flatten().all(|x| x.is_finite()) && det.is_finite() && det != 0.0)
    };
    if matrices.is_some_and(|mut m| m.any(|c| singular(&c))) {
        return Err(bad(
            "has an inverse bind matrix that is not finite or not invertible".into(),
            "export the avatar again (its skin's bind pose is damaged)",
        ));
    }
    let joints: Vec<gltf::Node> = skin.joints().collect();
    let order = parents_first(doc, &joints);
    // Position of each joint (in the skin's list) in `order`.
    let mut rank = vec![0usize; joints.len()];
    for (r, &k) in order.iter().enumerate() {
        rank[k] = r;
    }
    let skeleton = skeleton(doc, &joints, &order, &rank, skin.reader(get));
    let (mesh, influences) = skinned_primitives(doc, skin.index(), &rank, &get, &bad)?;
    let clips = clips(doc, &joints, &rank, &get, &bad)?;
    if clips.is_empty() {
        return Err(bad(
            "has no animation of its joints".into(),
            "export the avatar with its animation (in Blender: Include > Animation), or give \
             its motion as a vertex cache (cache = \"walk.pc2\" beside an OBJ body)",
        ));
    }
    Ok(SkinnedMesh {
        mesh,
        influences,
        skeleton,
        clips,
    })
}

/// The file's buffers: the GLB's binary chunk and external `.bin` files.
fn load_buffers(
    gltf: &gltf::Gltf,
    folder: Option<&Path>,
    name: &Path,
    key: &str,
) -> Result<Vec<Vec<u8>>, InputError> {
    let mut out = Vec::new();
    for b in gltf.document.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                InputError::new(
                    name,
                    key,
                    "names a binary chunk that the file does not have",
                    "export the avatar again as .glb",
                )
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                return Err(InputError::new(
                    name,
                    key,
                    "keeps its buffers inside the JSON (data: URIs), which drapekit does not read",
                    "export as .glb (glTF Binary), or as .gltf with a separate .bin",
                ))
            }
            gltf::buffer::Source::Uri(uri) => {
                let path = folder.unwrap_or(Path::new(".")).join(uri);
                std::fs::read(&path).map_err(|e| {
                    InputError::new(
                        name,
                        key,
                        format!("cannot read its buffer {}: {e}", path.display()),
                        "keep the .bin file beside the .gltf, or export as .glb",
                    )
                })?
            }
        };
        if data.len() < b.length() {
            return Err(InputError::new(
                name,
                key,
                format!(
                    "buffer {} holds {} bytes, fewer than the {} it declares",
                    b.index(),
                    data.len(),
                    b.length()
                ),
                "export the avatar again (the file is truncated)",
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Whether `acc` can be read as `what` (its data types `types`, its shape `dims`): the gltf
/// crate's readers assume a valid file and panic on a component type or a stride they do not
/// expect, so every accessor is checked before it is read. Sparse accessors are not read.
fn readable(
    acc: &gltf::Accessor,
    types: &[DataType],
    dims: Dimensions,
    what: &str,
    bad: &impl Fn(String, &str) -> InputError,
) -> Result<(), InputError> {
    let fix = "export the avatar again as glTF 2.0 (the file does not follow the format)";
    if !types.contains(&acc.data_type()) || acc.dimensions() != dims {
        return Err(bad(
            format!(
                "accessor {} ({what}) holds {:?} {:?}, where glTF allows {dims:?} of {types:?}",
                acc.index(),
                acc.dimensions(),
                acc.data_type()
            ),
            fix,
        ));
    }
    if acc.sparse().is_some() {
        return Err(bad(
            format!(
                "accessor {} ({what}) is sparse, which drapekit does not read",
                acc.index()
            ),
            "export the avatar without sparse accessors",
        ));
    }
    let Some(view) = acc.view() else {
        return Ok(());
    };
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    // The last element's end, past the accessor's start in its view.
    let end = (acc.count().checked_sub(1))
        .and_then(|k| k.checked_mul(stride))
        .and_then(|b| b.checked_add(size))
        .and_then(|b| b.checked_add(acc.offset()));
    match end {
        Some(end) if stride >= size && end <= view.length() => Ok(()),
        _ => Err(bad(
            format!(
                "accessor {} ({what}) has {} elements of {size} bytes every {stride} bytes from \
                 byte {}, which do not fit its {}-byte buffer view",
                acc.index(),
                acc.count(),
                acc.offset(),
                view.length()
            ),
            fix,
        )),
    }
}

/// Refuses a node hierarchy in which a node is its own ancestor (the gltf crate does not check,
/// and walking up such a tree never ends).
fn no_cycle(
    doc: &gltf::Document,
    bad: &impl Fn(String, &str) -> InputError,
) -> Result<(), InputError> {
    let parent = parents(doc);
    for n in doc.nodes() {
        let mut node = n.index();
        for _ in 0..=doc.nodes().len() {
            match parent.get(&node) {
                Some(&p) if p == n.index() => {
                    return Err(bad(
                        format!(
                            "node {} is its own ancestor (its children lead back to it)",
                            n.index()
                        ),
                        "export the avatar again: glTF nodes form a tree",
                    ))
                }
                Some(&p) => node = p,
                None => break,
            }
        }
    }
    Ok(())
}

/// Each node's parent.
fn parents(doc: &gltf::Document) -> HashMap<usize, usize> {
    let mut parent = HashMap::new();
    for n in doc.nodes() {
        for c in n.children() {
            parent.insert(c.index(), n.index());
        }
    }
    parent
}

/// The skin's joints (indices into its list) ordered so that every joint comes after the
/// joints above it.
fn parents_first(doc: &gltf::Document, joints: &[gltf::Node]) -> Vec<usize> {
    let parent = parents(doc);
    let depth = |mut node: usize| {
        let mut d = 0;
        while let Some(&p) = parent.get(&node) {
            node = p;
            d += 1;
            if d > doc.nodes().len() {
                break; // a cycle, which validation rules out
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..joints.len()).collect();
    order.sort_by_key(|&k| (depth(joints[k].index()), k));
    order
}

fn local(node: &gltf::Node) -> Trs {
    let (t, r, s) = node.transform().decomposed();
    Trs {
        translation: Vec3::from(t),
        rotation: Quat::from_array(r).normalize(),
        scale: Vec3::from(s),
    }
}

/// The skeleton in `order`: parents are the nearest joint above each joint, with the fixed
/// transforms of non-joint nodes between them (an armature's object transform) as `base`.
fn skeleton<'a, 's, F>(
    doc: &gltf::Document,
    joints: &[gltf::Node],
    order: &[usize],
    rank: &[usize],
    reader: gltf::skin::Reader<'a, 's, F>,
) -> Skeleton
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let parent = parents(doc);
    let joint_of: HashMap<usize, usize> = (joints.iter().enumerate())
        .map(|(k, n)| (n.index(), k))
        .collect();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let inverse_bind: Vec<Mat4> = match reader.read_inverse_bind_matrices() {
        Some(m) => m.map(|c| Mat4::from_cols_array_2d(&c)).collect(),
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    let mut s = Skeleton {
        names: Vec::new(),
        parents: Vec::new(),
        rest: Vec::new(),
        inverse_bind: Vec::new(),
        base: Vec::new(),
    };
    for &k in order {
        let node = &joints[k];
        s.names.push(
            node.name()
                .map_or_else(|| format!("joint{k}"), String::from),
        );
        s.rest.push(local(node));
        s.inverse_bind
            .push(inverse_bind.get(k).copied().unwrap_or(Mat4::IDENTITY));
        // Walk up to the nearest joint, collecting the fixed nodes on the way.
        let mut base = Mat4::IDENTITY;
        let mut above = parent.get(&node.index()).copied();
        let mut parent_joint = None;
        while let Some(p) = above {
            if let Some(&j) = joint_of.get(&p) {
                parent_joint = Some(rank[j]);
                break;
            }
            base = local(&nodes[p]).matrix() * base;
            above = parent.get(&p).copied();
        }
        s.parents.push(parent_joint);
        s.base.push(base);
    }
    s
}

/// Every triangle primitive of every mesh node that the skin moves, merged, welded where
/// vertices coincide, with each vertex's influences (joint indices in skeleton order).
fn skinned_primitives<'s>(
    doc: &gltf::Document,
    skin: usize,
    rank: &[usize],
    get: &(impl Clone + Fn(gltf::Buffer) -> Option<&'s [u8]>),
    bad: &impl Fn(String, &str) -> InputError,
) -> Result<(TriMesh, Vec<Influence>), InputError> {
    let mut mesh = TriMesh::default();
    let mut influences = Vec::new();
    let skinned = doc
        .nodes()
        .filter(|n| n.skin().is_some_and(|s| s.index() == skin));
    for node in skinned {
        let Some(m) = node.mesh() else { continue };
        let mesh_name = m
            .name()
            .map_or_else(|| format!("{}", m.index()), String::from);
        for prim in m.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let attributes = [
                (
                    gltf::Semantic::Positions,
                    &[DataType::F32][..],
                    Dimensions::Vec3,
                ),
                (
                    gltf::Semantic::Joints(0),
                    &[DataType::U8, DataType::U16],
                    Dimensions::Vec4,
                ),
                (
                    gltf::Semantic::Weights(0),
                    &[DataType::F32, DataType::U8, DataType::U16],
                    Dimensions::Vec4,
                ),
            ];
            for (semantic, types, dims) in attributes {
                if let Some(acc) = prim.get(&semantic) {
                    let what = format!("mesh '{mesh_name}' {semantic:?}");
                    readable(&acc, types, dims, &what, bad)?;
                }
            }
            if let Some(acc) = prim.indices() {
                let (types, what) = ([DataType::U8, DataType::U16, DataType::U32], "indices");
                readable(&acc, &types, Dimensions::Scalar, what, bad)?;
            }
            let r = prim.reader(get.clone());
            let missing = |what: &str| {
                bad(
                    format!("mesh '{mesh_name}' has no {what}"),
                    "export the avatar again with its skin weights",
                )
            };
            let positions: Vec<Vec3> = r
                .read_positions()
                .ok_or_else(|| missing("POSITION"))?
                .map(Vec3::from)
                .collect();
            let joints: Vec<[u16; 4]> = r
                .read_joints(0)
                .ok_or_else(|| missing("JOINTS_0"))?
                .into_u16()
                .collect();
            let weights: Vec<[f32; 4]> = r
                .read_weights(0)
                .ok_or_else(|| missing("WEIGHTS_0"))?
                .into_f32()
                .collect();
            if joints.len() != positions.len() || weights.len() != positions.len() {
                return Err(bad(
                    format!(
                        "mesh '{mesh_name}' has {} positions but {} joint and {} weight sets",
                        positions.len(),
                        joints.len(),
                        weights.len()
                    ),
                    "export the avatar again (its attributes disagree)",
                ));
            }
            let base = mesh.positions.len() as u32;
            for (v, (js, ws)) in joints.iter().zip(&weights).enumerate() {
                let mut pairs = Vec::new();
                for (&j, &w) in js.iter().zip(ws) {
                    if w == 0.0 {
                        continue;
                    }
                    let Some(&r) = rank.get(j as usize) else {
                        return Err(bad(
                            format!(
                                "vertex {v} of mesh '{mesh_name}' is weighted to joint {j}, but \
                                 the skin has only {} joints",
                                rank.len()
                            ),
                            "export the avatar again: its skin and mesh disagree (in Blender, \
                             apply the armature modifier's vertex groups to existing bones)",
                        ));
                    };
                    if !w.is_finite() || w < 0.0 {
                        return Err(bad(
                            format!("vertex {v} of mesh '{mesh_name}' has weight {w}"),
                            "export the avatar again with normalised, non-negative weights",
                        ));
                    }
                    pairs.push((r as u16, w));
                }
                let inf = Influence::strongest(pairs).ok_or_else(|| {
                    bad(
                        format!("vertex {v} of mesh '{mesh_name}' has no weight on any joint"),
                        "weight every vertex to some bone before exporting",
                    )
                })?;
                influences.push(inf);
            }
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(bad(
                    format!("vertex {i} of mesh '{mesh_name}' has a non-finite coordinate"),
                    "repair the mesh: every coordinate must be a finite number",
                ));
            }
            mesh.positions.extend(positions);
            let count = mesh.positions.len() as u32 - base;
            let indices: Vec<u32> = match r.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..count).collect(),
            };
            for t in indices.chunks_exact(3) {
                if t.iter().any(|&i| i >= count) {
                    return Err(bad(
                        format!("mesh '{mesh_name}' has an index past its {count} vertices"),
                        "export the avatar again",
                    ));
                }
                mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            }
        }
    }
    if mesh.triangles.is_empty() {
        return Err(bad(
            "has a skin but no triangle mesh that it moves".into(),
            "export the skinned mesh together with its armature",
        ));
    }
    // UV seams split vertices; weld them back so that the body is closed. A welded vertex keeps
    // the influences of its first copy (copies of one vertex carry the same weights).
    let remap = mesh.weld_map();
    let mut welded = vec![Influence::default(); mesh.positions.len()];
    for (old, &new) in remap.iter().enumerate().rev() {
        welded[new as usize] = influences[old];
    }
    Ok((mesh, welded))
}

/// Every animation with channels on the skin's joints.
fn clips<'s>(
    doc: &gltf::Document,
    joints: &[gltf::Node],
    rank: &[usize],
    get: &(impl Clone + Fn(gltf::Buffer) -> Option<&'s [u8]>),
    bad: &impl Fn(String, &str) -> InputError,
) -> Result<Vec<Clip>, InputError> {
    let joint_of: HashMap<usize, usize> = (joints.iter().enumerate())
        .map(|(k, n)| (n.index(), rank[k]))
        .collect();
    let mut out = Vec::new();
    for a in doc.animations() {
        let name = a
            .name()
            .map_or_else(|| format!("animation{}", a.index()), String::from);
        let mut channels = Vec::new();
        for c in a.channels() {
            let Some(&joint) = joint_of.get(&c.target().node().index()) else {
                continue;
            };
            let what = format!("animation '{name}' channel {}", c.index());
            let sampler = c.sampler();
            readable(
                &sampler.input(),
                &[DataType::F32],
                Dimensions::Scalar,
                &what,
                bad,
            )?;
            let output = match c.target().property() {
                Property::Translation | Property::Scale => (&[DataType::F32][..], Dimensions::Vec3),
                Property::Rotation => (
                    &[
                        DataType::F32,
                        DataType::I8,
                        DataType::U8,
                        DataType::I16,
                        DataType::U16,
                    ][..],
                    Dimensions::Vec4,
                ),
                Property::MorphTargetWeights => continue,
            };
            readable(&sampler.output(), output.0, output.1, &what, bad)?;
            let r = c.reader(get.clone());
            let (Some(times), Some(outputs)) = (r.read_inputs(), r.read_outputs()) else {
                continue;
            };
            let times: Vec<f32> = times.collect();
            let values = match outputs {
                ReadOutputs::Translations(v) => Values::Translation(v.map(Vec3::from).collect()),
                ReadOutputs::Scales(v) => Values::Scale(v.map(Vec3::from).collect()),
                ReadOutputs::Rotations(v) => {
                    Values::Rotation(v.into_f32().map(Quat::from_array).collect())
                }
                ReadOutputs::MorphTargetWeights(_) => continue,
            };
            let interpolation = match c.sampler().interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            let count = match &values {
                Values::Translation(v) | Values::Scale(v) => v.len(),
                Values::Rotation(v) => v.len(),
            };
            let sorted = times.windows(2).all(|w| w[0] <= w[1]);
            let finite = times.iter().all(|t| t.is_finite());
            // A rotation key must be a rotation: of finite, non-zero length (it is normalised
            // when played). A cubic spline's tangents (the first and third of each key's three
            // values) need only be finite: zero tangents are common.
            let good_values = match &values {
                Values::Translation(v) | Values::Scale(v) => v.iter().all(|x| x.is_finite()),
                Values::Rotation(v) => v.iter().enumerate().all(|(k, q)| {
                    let tangent = per_key == 3 && k % 3 != 1;
                    let len = q.length();
                    q.is_finite() && (tangent || (len.is_finite() && len > 0.0))
                }),
            };
            if !good_values {
                return Err(bad(
                    format!(
                        "animation '{name}' has a key value that is not a finite number, or a \
                         rotation whose length is zero or not finite"
                    ),
                    "export the animation again (bake it to keyframes)",
                ));
            }
            if times.is_empty() || count != per_key * times.len() || !sorted || !finite {
                return Err(bad(
                    format!(
                        "animation '{name}' has a channel with {} key times (sorted: {sorted}, \
                         finite: {finite}) and {count} values",
                        times.len()
                    ),
                    "export the animation again (bake it to keyframes)",
                ));
            }
            channels.push(Channel {
                joint,
                times,
                values,
                interpolation,
            });
        }
        if !channels.is_empty() {
            out.push(Clip { name, channels });
        }
    }
    Ok(out)
}
