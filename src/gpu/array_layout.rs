//! Where the GPU path keeps its arrays: in 2D textures or in storage buffers, one switch for
//! every kernel.
//!
//! The kernels are written once, against textures (`textureLoad(a, texel(i), 0)`,
//! `textureStore(a, texel(i), v)`), because software adapters such as lavapipe fetch a texel as
//! one vector while they read a storage buffer lane by lane. Real GPUs, and every peer solver,
//! read storage buffers. With [`ArrayLayout::Buffers`] each texel array becomes a storage
//! buffer of the same bytes (a texture's rows are contiguous, so element `i` sits at byte
//! `i × texel size` either way) and [`bind_as_buffers`] rewrites the kernel's declarations and
//! accesses of those arrays before the shader is compiled. Nothing else differs: the same
//! arithmetic runs on the same values.
//!
//! An array whose kernels need it as a texture says so where the arrays are listed
//! (`Elements::layout`): the body's signed distance field stays a texture in both layouts.

use super::pipelines::Binding;

/// How texel arrays are stored on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayLayout {
    /// 2D textures `TEXELS_PER_ROW` wide (fastest on software adapters).
    Textures,
    /// Storage buffers (what GPUs read fastest; measured in the book's hardware chapter).
    Buffers,
}

/// Storage buffers per shader stage the buffer layout asks of a device: the most texel arrays
/// and solve buffers one kernel binds (contact_planes: 18 bindings) with room to spare.
pub const BUFFER_LAYOUT_STORAGE_BUFFERS: u32 = 24;

impl ArrayLayout {
    /// `DRAPEKIT_GPU_LAYOUT` (`textures` or `buffers`) if set, else textures on software
    /// adapters and buffers on GPUs that bind enough storage buffers per kernel.
    pub fn choose(info: &wgpu::AdapterInfo, limits: &wgpu::Limits) -> Result<Self, String> {
        let enough = ArrayLayout::Buffers.check(info, limits).is_ok();
        match std::env::var("DRAPEKIT_GPU_LAYOUT").as_deref() {
            Ok("textures") => Ok(ArrayLayout::Textures),
            Ok("buffers") => ArrayLayout::Buffers.check(info, limits),
            Ok("") | Err(_) if info.device_type == wgpu::DeviceType::Cpu || !enough => {
                Ok(ArrayLayout::Textures)
            }
            Ok("") | Err(_) => Ok(ArrayLayout::Buffers),
            Ok(other) => Err(format!(
                "DRAPEKIT_GPU_LAYOUT={other:?} is not a layout; use textures or buffers, or \
                 unset it for the adapter's default"
            )),
        }
    }

    /// `self`, if the adapter can bind it.
    pub fn check(self, info: &wgpu::AdapterInfo, limits: &wgpu::Limits) -> Result<Self, String> {
        let bound = limits.max_storage_buffers_per_shader_stage;
        match self {
            ArrayLayout::Buffers if bound < BUFFER_LAYOUT_STORAGE_BUFFERS => Err(format!(
                "the buffer layout needs {BUFFER_LAYOUT_STORAGE_BUFFERS} storage buffers per \
                 kernel but {:?} binds {bound}; unset DRAPEKIT_GPU_LAYOUT or set it to textures",
                info.name
            )),
            layout => Ok(layout),
        }
    }

    /// How many of a matrix row's blocks an invocation of the multigrid kernels loads at once
    /// (`BLOCKS_IN_FLIGHT` in multigrid.wgsl; the same numbers either way). GPUs hide a load's
    /// latency with other loads in flight, and a coarse level's rows of dozens of blocks are
    /// where the implicit solve waits. Software adapters run invocations in SIMD lanes, where
    /// four in flight cost more than they hide: the cotton T-shirt's first four frames on
    /// lavapipe took 3.9–4.6 s with four against 3.5–3.8 s with one.
    pub fn blocks_in_flight(self) -> u32 {
        match self {
            ArrayLayout::Textures => 1,
            ArrayLayout::Buffers => 4,
        }
    }

    /// The name summaries and benchmarks print.
    pub fn name(self) -> &'static str {
        match self {
            ArrayLayout::Textures => "textures",
            ArrayLayout::Buffers => "buffers",
        }
    }
}

/// The element type of a buffer-backed array in WGSL, and whether it is a scalar.
fn element_type(format: wgpu::TextureFormat) -> (&'static str, bool) {
    use wgpu::TextureFormat::*;
    match format {
        Rgba32Float => ("vec4<f32>", false),
        R32Float => ("f32", true),
        Rgba32Uint => ("vec4<u32>", false),
        R32Uint => ("u32", true),
        other => unreachable!("texel arrays never use {other:?}"),
    }
}

/// One array the rewrite turns into a storage buffer.
struct BufferArray {
    name: String,
    /// WGSL element type, e.g. `vec4<f32>`.
    element: &'static str,
    /// A one-component format: loads splat it to the vec4 a `textureLoad` returns (whose `.x`
    /// the kernels read), stores keep the `.x` a `textureStore` keeps.
    scalar: bool,
}

/// `source` with every buffer-backed texel array of `groups` (each group's number and its
/// numbered bindings) declared as a storage buffer and accessed by index. A source whose
/// bindings are all textures comes back unchanged.
pub fn bind_as_buffers(source: String, groups: &[(u32, &[(u32, Binding)])]) -> String {
    let mut source = source;
    let mut arrays = Vec::new();
    for &(group, bindings) in groups {
        for &(binding, b) in bindings {
            let (t, access) = match b {
                Binding::Read(t) => (t, "read"),
                Binding::Write(t) => (t, "read_write"),
                _ => continue,
            };
            if !t.is_buffer() {
                continue;
            }
            let (element, scalar) = element_type(t.format);
            let name = redeclare(&mut source, group, binding, access, element);
            arrays.push(BufferArray {
                name,
                element,
                scalar,
            });
        }
    }
    for array in &arrays {
        source = rewrite_calls(&source, array);
    }
    source
}

/// Replaces the declaration at `@group(group) @binding(binding)` by a storage buffer of
/// `element`s and returns the variable's name. Panics when the kernel has no such declaration:
/// the binding lists and the kernels are written together, so that is a bug.
fn redeclare(source: &mut String, group: u32, binding: u32, access: &str, element: &str) -> String {
    let marker = format!("@group({group}) @binding({binding}) var ");
    let start = (source.find(&marker)).unwrap_or_else(|| panic!("no declaration {marker}"));
    let name_start = start + marker.len();
    let rest = &source[name_start..];
    let colon = rest.find(':').expect("a declaration has a type");
    let end = rest.find(';').expect("a declaration ends with ;");
    let name = rest[..colon].trim().to_string();
    let declaration = format!(
        "@group({group}) @binding({binding}) var<storage, {access}> {name}: array<{element}>"
    );
    source.replace_range(start..name_start + end, &declaration);
    name
}

/// Rewrites `textureLoad(name, texel(e), 0)` and `textureStore(name, texel(e), v)`.
fn rewrite_calls(source: &str, array: &BufferArray) -> String {
    let load = format!("textureLoad({}, texel(", array.name);
    let store = format!("textureStore({}, texel(", array.name);
    let mut out = String::with_capacity(source.len());
    let mut rest = source;
    loop {
        let next = [(rest.find(&load), true), (rest.find(&store), false)]
            .into_iter()
            .filter_map(|(at, is_load)| at.map(|at| (at, is_load)))
            .min();
        let Some((at, is_load)) = next else {
            out.push_str(rest);
            return out;
        };
        out.push_str(&rest[..at]);
        let prefix = if is_load { &load } else { &store };
        let after = &rest[at + prefix.len()..];
        let index_end = closing_paren(after);
        let index = &after[..index_end];
        // After `texel(e)`: `, 0)` for a load, `, v)` for a store.
        let tail = after[index_end + 1..].trim_start();
        let tail = tail
            .strip_prefix(',')
            .expect("texel(e) is followed by an argument");
        let call_end = closing_paren(tail);
        let argument = tail[..call_end].trim();
        let name = &array.name;
        if is_load {
            assert_eq!(argument, "0", "{name}: textureLoad of mip level 0 only");
            match array.scalar {
                true => out.push_str(&format!("vec4<{}>({name}[{index}])", array.element)),
                false => out.push_str(&format!("{name}[{index}]")),
            }
        } else {
            match array.scalar {
                true => out.push_str(&format!("{name}[{index}] = ({argument}).x")),
                false => out.push_str(&format!("{name}[{index}] = {argument}")),
            }
        }
        rest = &tail[call_end + 1..];
    }
}

/// The byte offset in `s` of the `)` that closes a parenthesis opened just before `s`.
fn closing_paren(s: &str) -> usize {
    let mut depth = 0usize;
    for (i, c) in s.char_indices() {
        match c {
            '(' => depth += 1,
            ')' if depth == 0 => return i,
            ')' => depth -= 1,
            _ => {}
        }
    }
    panic!("unbalanced parentheses in a kernel: {s:.60}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rewritten(source: &str, name: &str, element: &'static str, scalar: bool) -> String {
        let array = BufferArray {
            name: name.into(),
            element,
            scalar,
        };
        rewrite_calls(source, &array)
    }

    #[test]
    fn loads_and_stores_become_indexing() {
        let src = "let p = textureLoad(pos, texel(i + f(j)), 0).xyz;\n\
                   textureStore(pos, texel(i), vec4<f32>(p, g(1.0)));";
        assert_eq!(
            rewritten(src, "pos", "vec4<f32>", false),
            "let p = pos[i + f(j)].xyz;\npos[i] = vec4<f32>(p, g(1.0));"
        );
    }

    #[test]
    fn scalar_arrays_splat_loads_and_keep_x_on_store() {
        let src = "let e = textureLoad(off, texel(i + 1u), 0).x; textureStore(off, texel(i), v);";
        assert_eq!(
            rewritten(src, "off", "u32", true),
            "let e = vec4<u32>(off[i + 1u]).x; off[i] = (v).x;"
        );
    }

    #[test]
    fn other_arrays_and_prefixes_are_left_alone() {
        let src = "textureLoad(pos2, texel(i), 0); textureLoad(sdf, texel(k), 0);";
        assert_eq!(rewritten(src, "pos", "vec4<f32>", false), src);
    }

    #[test]
    fn declarations_become_storage_buffers() {
        let mut src = "@group(0) @binding(3) var springs: texture_2d<u32>; // one per texel\n\
                       @group(1) @binding(0) var out: texture_storage_2d<rgba32float, write>;"
            .to_string();
        assert_eq!(redeclare(&mut src, 0, 3, "read", "vec4<u32>"), "springs");
        assert_eq!(redeclare(&mut src, 1, 0, "read_write", "vec4<f32>"), "out");
        assert_eq!(
            src,
            "@group(0) @binding(3) var<storage, read> springs: array<vec4<u32>>; // one per \
             texel\n@group(1) @binding(0) var<storage, read_write> out: array<vec4<f32>>;"
        );
    }
}
