//! Binary glTF 2.0 (`.glb`) output and input, through the `gltf` crate.
//!
//! glTF is what game engines import. A mesh becomes one scene with one node and one mesh of one
//! triangle primitive:
//!
//! ```text
//!  GLB = header | JSON chunk | BIN chunk
//!  BIN = positions (f32 x3 per vertex) | normals (f32 x3, if any) | indices (u32 x3 per triangle)
//!        each part starts on a 4-byte boundary (the parts are multiples of 4 bytes anyway)
//! ```
//!
//! A mesh without triangles becomes a scene with one empty node and no buffer (glTF allows no
//! empty accessor), so its vertices, which no triangle uses, are not written.
//!
//! The JSON is built with `gltf-json` (re-exported by `gltf`) and framed by
//! [`gltf::binary::Glb`], so the layout rules of the format (chunk alignment, padding, the
//! position accessor's `min`/`max`, buffer-view targets) are the crate's, not ours. Bytes are
//! deterministic: the same mesh always gives the same file.
//!
//! ```
//! use rmt_mesh::{glb, Mesh};
//! let mesh = Mesh::from_triangles(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
//!     vec![0, 1, 2],
//! );
//! let bytes = glb::to_glb(&mesh).unwrap();
//! assert_eq!(&bytes[..4], b"glTF");
//! assert_eq!(glb::from_glb(&bytes).unwrap(), mesh);
//! ```

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io;

use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;

use crate::Mesh;

/// Why a `.glb` could not be written or read (the caller adds the file name).
#[derive(Debug, thiserror::Error)]
pub enum GlbError {
    /// The mesh cannot be written: mismatched normals, bad indices, or more than the 4 GiB a
    /// binary glTF file may hold.
    #[error("{0}")]
    Invalid(String),
    /// The `gltf` crate rejected the bytes (not binary glTF, truncated, bad JSON).
    #[error("not a valid binary glTF file: {0}")]
    Format(#[from] gltf::Error),
    /// The file is valid glTF but holds no triangle mesh this reader understands.
    #[error("{0}")]
    Unsupported(String),
}

/// The mesh as a binary glTF file (see the [module documentation](self)).
pub fn to_glb(mesh: &Mesh) -> Result<Vec<u8>, GlbError> {
    let normals = crate::check_writable(mesh).map_err(|e| GlbError::Invalid(e.to_string()))?;
    let vertex_bytes = mesh.positions.len() * 12;
    let normal_bytes = if normals { vertex_bytes } else { 0 };
    let index_bytes = mesh.indices.len() * 4;
    let total = vertex_bytes + normal_bytes + index_bytes;
    // The whole file's length is a u32; leave room for the header and the JSON chunk.
    if total > (u32::MAX as usize) - (1 << 20) {
        return Err(GlbError::Invalid(format!(
            "the mesh needs {total} bytes of buffer data, more than a binary glTF file can hold"
        )));
    }

    let mut bin = Vec::with_capacity(total);
    for p in &mesh.positions {
        p.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
    }
    if normals {
        for n in &mesh.normals {
            n.iter()
                .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
        }
    }
    for i in &mesh.indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }

    let mut root = json::Root::default();
    root.asset.generator = Some("rmt-mesh".into());
    if mesh.indices.is_empty() {
        let node = root.push(json::Node::default());
        let scene = root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes: vec![node],
        });
        root.scene = Some(scene);
        return frame(&root, None);
    }
    let buffer = root.push(json::Buffer {
        byte_length: USize64::from(total),
        extensions: None,
        extras: Default::default(),
        name: None,
        uri: None,
    });
    let view = |root: &mut json::Root, offset: usize, length: usize, target| {
        root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(length),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: Default::default(),
            name: None,
            target: Some(Valid(target)),
        })
    };
    let position_view = view(
        &mut root,
        0,
        vertex_bytes,
        json::buffer::Target::ArrayBuffer,
    );
    let normal_view = normals.then(|| {
        view(
            &mut root,
            vertex_bytes,
            normal_bytes,
            json::buffer::Target::ArrayBuffer,
        )
    });
    let index_view = view(
        &mut root,
        vertex_bytes + normal_bytes,
        index_bytes,
        json::buffer::Target::ElementArrayBuffer,
    );

    let accessor = |root: &mut json::Root, view, count: usize, component, ty, bounds| {
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(json::Value::from(lo)), Some(json::Value::from(hi))),
            None => (None, None),
        };
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    };
    let (lo, hi) = bounds(&mesh.positions);
    let positions = accessor(
        &mut root,
        position_view,
        mesh.positions.len(),
        json::accessor::ComponentType::F32,
        json::accessor::Type::Vec3,
        Some((lo.to_vec(), hi.to_vec())),
    );
    let normal_accessor = normal_view.map(|v| {
        accessor(
            &mut root,
            v,
            mesh.positions.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            None,
        )
    });
    let indices = accessor(
        &mut root,
        index_view,
        mesh.indices.len(),
        json::accessor::ComponentType::U32,
        json::accessor::Type::Scalar,
        None,
    );

    let mut attributes = BTreeMap::new();
    attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
    if let Some(n) = normal_accessor {
        attributes.insert(Valid(json::mesh::Semantic::Normals), n);
    }
    let gltf_mesh = root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: None,
        primitives: vec![json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        }],
        weights: None,
    });
    let node = root.push(json::Node {
        mesh: Some(gltf_mesh),
        ..Default::default()
    });
    let scene = root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: None,
        nodes: vec![node],
    });
    root.scene = Some(scene);
    frame(&root, Some(bin))
}

/// The GLB container of `root` and its binary chunk.
fn frame(root: &json::Root, bin: Option<Vec<u8>>) -> Result<Vec<u8>, GlbError> {
    let json_text = json::serialize::to_vec(root)
        .map_err(|e| GlbError::Invalid(format!("cannot serialise the glTF JSON: {e}")))?;
    let glb = gltf::binary::Glb {
        // `to_writer` computes the header's length itself; these fields are only read back.
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: Cow::Owned(json_text),
        bin: bin.map(Cow::Owned),
    };
    Ok(glb.to_vec()?)
}

/// Writes `mesh` as binary glTF to `out` (see [`to_glb`]).
pub fn write_glb<W: io::Write>(mut out: W, mesh: &Mesh) -> io::Result<()> {
    let bytes = to_glb(mesh).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
    out.write_all(&bytes)?;
    out.flush()
}

/// Reads a binary glTF file's triangle primitives into one mesh: positions, normals when every
/// primitive has them, indices (non-indexed primitives get `0..n`). Node transforms are not
/// applied (what [`to_glb`] writes has none).
///
/// The container and the JSON are parsed by the `gltf` crate, but the accessors are read here,
/// with every index, offset, stride and length checked. The crate's validation and readers
/// trust some of what a damaged file says (gltf 1.4 indexes `accessors` with a primitive's
/// POSITION index unchecked, and reaches `unreachable!()` for an index accessor of a float
/// type), so they would panic on bad input instead of returning an error.
pub fn from_glb(bytes: &[u8]) -> Result<Mesh, GlbError> {
    let glb = gltf::Glb::from_slice(bytes)?;
    let root: json::Root = json::deserialize::from_slice(&glb.json)
        .map_err(|e| GlbError::Format(gltf::Error::Deserialize(e)))?;
    let blob = glb.bin.as_deref();
    let mut mesh = Mesh::default();
    let mut all_normals = true;
    let mut normals = Vec::new();
    for (m, gltf_mesh) in root.meshes.iter().enumerate() {
        for primitive in &gltf_mesh.primitives {
            match primitive.mode {
                Valid(json::mesh::Mode::Triangles) => {}
                Valid(mode) => {
                    return Err(GlbError::Unsupported(format!(
                        "mesh {m} has a primitive of mode {mode:?}; only triangles are read"
                    )))
                }
                _ => {
                    return Err(GlbError::Unsupported(format!(
                        "mesh {m} has a primitive of an unknown mode"
                    )))
                }
            }
            let attribute = |semantic| primitive.attributes.get(&Valid(semantic));
            let Some(&position_accessor) = attribute(json::mesh::Semantic::Positions) else {
                return Err(GlbError::Unsupported(format!(
                    "mesh {m} has a primitive without positions"
                )));
            };
            let base = mesh.positions.len();
            read_accessor(&root, blob, position_accessor, Kind::Vec3F32, &mut |c| {
                mesh.positions.push([c[0] as f32, c[1] as f32, c[2] as f32])
            })?;
            let added = mesh.positions.len() - base;
            match attribute(json::mesh::Semantic::Normals) {
                Some(&n) if all_normals => {
                    let before = normals.len();
                    read_accessor(&root, blob, n, Kind::Vec3F32, &mut |c| {
                        normals.push([c[0] as f32, c[1] as f32, c[2] as f32])
                    })?;
                    if normals.len() - before != added {
                        return Err(GlbError::Unsupported(format!(
                            "mesh {m}: {} normals for {added} positions",
                            normals.len() - before
                        )));
                    }
                }
                _ => all_normals = false,
            }
            if u32::try_from(mesh.positions.len()).is_err() {
                return Err(GlbError::Unsupported("more than 2^32 vertices".into()));
            }
            let first = base as u32;
            match primitive.indices {
                Some(index_accessor) => {
                    let mut bad = None;
                    read_accessor(&root, blob, index_accessor, Kind::Index, &mut |c| {
                        let i = c[0] as usize;
                        if i >= added {
                            bad.get_or_insert(i);
                        } else {
                            mesh.indices.push(first + i as u32);
                        }
                    })?;
                    if let Some(i) = bad {
                        return Err(GlbError::Unsupported(format!(
                            "mesh {m}: index {i} out of range for {added} vertices"
                        )));
                    }
                }
                None => mesh.indices.extend((0..added as u32).map(|i| first + i)),
            }
        }
    }
    if mesh.indices.len() % 3 != 0 {
        return Err(GlbError::Unsupported(format!(
            "{} indices is not a whole number of triangles",
            mesh.indices.len()
        )));
    }
    if all_normals && normals.len() == mesh.positions.len() {
        mesh.normals = normals;
    }
    Ok(mesh)
}

/// What [`read_accessor`] accepts.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Three `f32` per element (positions, normals).
    Vec3F32,
    /// One unsigned integer of 8, 16 or 32 bits per element (triangle indices).
    Index,
}

/// Calls `each` with every element of accessor `index`, read from the GLB's binary chunk, after
/// checking the accessor's type, its buffer view and every byte range it covers. Components
/// arrive widened to `f64` (exact for `f32` and for `u32`).
fn read_accessor(
    root: &json::Root,
    blob: Option<&[u8]>,
    index: json::Index<json::Accessor>,
    kind: Kind,
    each: &mut dyn FnMut([f64; 3]),
) -> Result<(), GlbError> {
    use json::accessor::{ComponentType as C, Type};
    let bad = |what: String| GlbError::Unsupported(format!("accessor {}: {what}", index.value()));
    let accessor = root
        .accessors
        .get(index.value())
        .ok_or_else(|| bad(format!("missing (the file has {})", root.accessors.len())))?;
    if accessor.sparse.is_some() {
        return Err(bad("sparse accessors are not read".into()));
    }
    let component = match accessor.component_type {
        Valid(json::accessor::GenericComponentType(c)) => c,
        _ => return Err(bad("unknown component type".into())),
    };
    let (width, components) = match (kind, component, accessor.type_) {
        (Kind::Vec3F32, C::F32, Valid(Type::Vec3)) => (4, 3),
        (Kind::Index, C::U8, Valid(Type::Scalar)) => (1, 1),
        (Kind::Index, C::U16, Valid(Type::Scalar)) => (2, 1),
        (Kind::Index, C::U32, Valid(Type::Scalar)) => (4, 1),
        (Kind::Vec3F32, ..) => return Err(bad("expected three f32 per element".into())),
        (Kind::Index, ..) => return Err(bad("expected unsigned integer scalars".into())),
    };
    let element = width * components;
    let count = usize::try_from(accessor.count.0).map_err(|_| bad("count too large".into()))?;
    if count == 0 {
        return Err(bad("no elements (glTF requires count >= 1)".into()));
    }
    let view_index = accessor
        .buffer_view
        .ok_or_else(|| bad("no buffer view (all-zero accessors are not read)".into()))?;
    let view = root
        .buffer_views
        .get(view_index.value())
        .ok_or_else(|| bad(format!("buffer view {} is missing", view_index.value())))?;
    let buffer = root
        .buffers
        .get(view.buffer.value())
        .ok_or_else(|| bad(format!("buffer {} is missing", view.buffer.value())))?;
    if buffer.uri.is_some() || view.buffer.value() != 0 {
        return Err(bad("external buffers are not read".into()));
    }
    let blob = blob.ok_or_else(|| bad("the file has no binary chunk".into()))?;
    let to_usize = |v: u64| usize::try_from(v).ok();
    let overflow = || bad("its byte range overflows".into());
    let stride = match view.byte_stride {
        Some(s) => s.0,
        None => element,
    };
    if stride < element {
        return Err(bad(format!(
            "stride {stride} is less than its element size {element}"
        )));
    }
    let view_start = to_usize(view.byte_offset.map_or(0, |o| o.0)).ok_or_else(overflow)?;
    let view_length = to_usize(view.byte_length.0).ok_or_else(overflow)?;
    let view_end = view_start.checked_add(view_length).ok_or_else(overflow)?;
    if view_end > blob.len() {
        return Err(bad(format!(
            "its buffer view ends at byte {view_end}, past the binary chunk's {} bytes",
            blob.len()
        )));
    }
    let offset = to_usize(accessor.byte_offset.map_or(0, |o| o.0)).ok_or_else(overflow)?;
    let needed = stride
        .checked_mul(count - 1)
        .and_then(|b| b.checked_add(element))
        .and_then(|b| b.checked_add(offset))
        .ok_or_else(overflow)?;
    if needed > view_length {
        return Err(bad(format!(
            "{count} elements need {needed} bytes of a {view_length}-byte buffer view"
        )));
    }
    let data = &blob[view_start + offset..view_start + needed];
    for e in 0..count {
        let at = &data[e * stride..e * stride + element];
        let mut c = [0.0f64; 3];
        for (k, value) in c.iter_mut().take(components).enumerate() {
            let b = &at[k * width..(k + 1) * width];
            *value = match *b {
                [b0] => b0 as f64,
                [b0, b1] => u16::from_le_bytes([b0, b1]) as f64,
                [b0, b1, b2, b3] if component == C::F32 => {
                    f32::from_le_bytes([b0, b1, b2, b3]) as f64
                }
                [b0, b1, b2, b3] => u32::from_le_bytes([b0, b1, b2, b3]) as f64,
                _ => 0.0, // no other width is accepted above
            };
        }
        each(c);
    }
    Ok(())
}

/// The component-wise minimum and maximum of `points` (zeros for no points).
fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    if points.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solids::tetrahedron;
    use proptest::prelude::*;

    #[test]
    fn a_glb_round_trips_with_and_without_normals() {
        let mut mesh = tetrahedron();
        assert_eq!(from_glb(&to_glb(&mesh).unwrap()).unwrap(), mesh);
        mesh.compute_area_weighted_normals();
        assert_eq!(from_glb(&to_glb(&mesh).unwrap()).unwrap(), mesh);
    }

    #[test]
    fn the_glb_is_deterministic_and_4_byte_aligned_with_bounds() {
        let mesh = tetrahedron();
        let a = to_glb(&mesh).unwrap();
        assert_eq!(a, to_glb(&mesh).unwrap());
        assert_eq!(a.len() % 4, 0);
        let length = u32::from_le_bytes([a[8], a[9], a[10], a[11]]) as usize;
        assert_eq!(length, a.len());
        let gltf = gltf::Gltf::from_slice(&a).unwrap();
        let accessor = gltf.accessors().next().unwrap();
        assert_eq!(accessor.min(), Some(serde_json::json!([0.0, 0.0, 0.0])));
        assert_eq!(accessor.max(), Some(serde_json::json!([1.0, 1.0, 1.0])));
    }

    #[test]
    fn a_bad_mesh_or_bad_bytes_give_errors() {
        let mut mesh = tetrahedron();
        mesh.indices.push(7);
        assert!(matches!(to_glb(&mesh), Err(GlbError::Invalid(_))));
        assert!(matches!(from_glb(b"glTF\x02"), Err(GlbError::Format(_))));
        assert!(matches!(from_glb(b"not a glb"), Err(GlbError::Format(_))));
        let mut bytes = to_glb(&tetrahedron()).unwrap();
        bytes.truncate(bytes.len() - 8);
        assert!(from_glb(&bytes).is_err());
    }

    proptest! {
        #[test]
        fn damaged_files_give_errors_not_panics(
            flips in prop::collection::vec((0usize..4096, any::<u8>()), 1..8),
            cut in 0usize..4096,
        ) {
            let mut mesh = tetrahedron();
            mesh.compute_area_weighted_normals();
            let mut bytes = to_glb(&mesh).unwrap();
            for (at, value) in flips {
                let n = bytes.len();
                bytes[at % n] = value;
            }
            bytes.truncate(bytes.len() - cut % 16);
            let _ = from_glb(&bytes);
        }

        #[test]
        fn out_of_range_accessor_indices_are_refused(index in 0usize..1000) {
            // A renumbered POSITION accessor used to panic inside gltf-json's validation.
            let bytes = to_glb(&tetrahedron()).unwrap();
            let glb = gltf::Glb::from_slice(&bytes).unwrap();
            let mut root: gltf::json::Root = gltf::json::deserialize::from_slice(&glb.json).unwrap();
            let n = root.accessors.len();
            let bad = n + index;
            for (_, a) in root.meshes[0].primitives[0].attributes.iter_mut() {
                *a = gltf::json::Index::new(bad as u32);
            }
            let frame = frame(&root, glb.bin.map(|b| b.into_owned())).unwrap();
            let err = from_glb(&frame).unwrap_err().to_string();
            prop_assert!(err.contains(&format!("accessor {bad}")), "{}", err);
        }

        #[test]
        fn any_writable_mesh_round_trips(
            positions in prop::collection::vec(prop::array::uniform3(-1e6f32..1e6), 1..40),
            picks in prop::collection::vec(0usize..1000, 0..60),
        ) {
            let n = positions.len();
            let triangles = picks.len() / 3 * 3;
            let indices = picks[..triangles].iter().map(|&i| (i % n) as u32).collect();
            let mesh = Mesh::from_triangles(positions, indices);
            let back = from_glb(&to_glb(&mesh).unwrap()).unwrap();
            if mesh.indices.is_empty() {
                // No triangle: nothing to write but an empty scene.
                prop_assert_eq!(back, Mesh::default());
            } else {
                prop_assert_eq!(back, mesh);
            }
        }
    }
}
