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
    let normals = crate::io::check_writable(mesh).map_err(|e| GlbError::Invalid(e.to_string()))?;
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
pub fn from_glb(bytes: &[u8]) -> Result<Mesh, GlbError> {
    let gltf = gltf::Gltf::from_slice(bytes)?;
    let blob = gltf.blob.as_deref();
    let mut mesh = Mesh::default();
    let mut all_normals = true;
    let mut normals = Vec::new();
    for m in gltf.meshes() {
        for primitive in m.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                return Err(GlbError::Unsupported(format!(
                    "mesh {} has a primitive of mode {:?}; only triangles are read",
                    m.index(),
                    primitive.mode()
                )));
            }
            // The gltf crate's readers assume accessors of at least one element (as the format
            // requires); refuse the others here instead of letting them reach it.
            let empty = primitive
                .attributes()
                .map(|(_, a)| a)
                .chain(primitive.indices())
                .find(|a| a.count() == 0);
            if let Some(a) = empty {
                return Err(GlbError::Unsupported(format!(
                    "accessor {} has no elements (glTF requires count >= 1)",
                    a.index()
                )));
            }
            let reader = primitive.reader(|buffer| match buffer.source() {
                gltf::buffer::Source::Bin => blob,
                gltf::buffer::Source::Uri(_) => None,
            });
            let Some(positions) = reader.read_positions() else {
                return Err(GlbError::Unsupported(format!(
                    "mesh {} has a primitive without readable positions (external buffers are \
                     not read)",
                    m.index()
                )));
            };
            let base = mesh.positions.len();
            mesh.positions.extend(positions);
            let added = mesh.positions.len() - base;
            match reader.read_normals() {
                Some(n) if all_normals => normals.extend(n),
                _ => all_normals = false,
            }
            let first = u32::try_from(base)
                .map_err(|_| GlbError::Unsupported("more than 2^32 vertices".into()))?;
            match reader.read_indices() {
                Some(indices) => {
                    for i in indices.into_u32() {
                        if i as usize >= added {
                            return Err(GlbError::Unsupported(format!(
                                "mesh {}: index {i} out of range for {added} vertices",
                                m.index()
                            )));
                        }
                        mesh.indices.push(first + i);
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
    use proptest::prelude::*;

    fn tetrahedron() -> Mesh {
        Mesh::from_triangles(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
        )
    }

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
