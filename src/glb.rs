//! The plumbing every glTF binary drapekit writes shares: buffer views in one 4-byte aligned
//! binary chunk, accessors over them, an empty node, and the GLB container. What goes into the
//! document (a garment and its morph targets, a skinned body) is each writer's own.

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use json::{accessor, buffer, Index};

/// A glTF document and its binary chunk, filled together.
#[derive(Default)]
pub struct GlbDoc {
    /// The JSON document.
    pub root: json::Root,
    /// The binary chunk the buffer views point into.
    pub bin: Vec<u8>,
}

impl GlbDoc {
    /// `bytes` appended to the binary chunk (4-byte aligned) as a buffer view.
    pub fn view(&mut self, bytes: &[u8], target: Option<buffer::Target>) -> Index<buffer::View> {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// An accessor of `count` elements of `kind` over `bytes` (little endian) in a view of its own.
    pub fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        kind: accessor::Type,
        component: accessor::ComponentType,
        bounds: Option<(json::Value, json::Value)>,
        target: Option<buffer::Target>,
    ) -> Index<json::Accessor> {
        let view = self.view(bytes, target);
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

    /// The GLB container: a 12-byte header, the JSON chunk (padded with spaces) and the binary
    /// chunk (padded with zeros), each 4-byte aligned; `None` past the format's 32-bit sizes.
    pub fn finish(mut self) -> Option<Vec<u8>> {
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

/// A node with nothing set.
pub fn node() -> json::Node {
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
