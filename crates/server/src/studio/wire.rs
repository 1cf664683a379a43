//! The studio's binary mesh replies: a JSON header (statistics, timings) and one or more mesh
//! parts (a whole extraction, or the chunks of a sculpt edit) as little-endian typed arrays that
//! the page views with `Float32Array` / `Uint32Array` without parsing numbers.
//!
//! ```text
//! offset  size         field
//! 0       4            magic "RMTS"
//! 4       4            format version (u32, 1)
//! 8       4            J = bytes of the JSON header (u32)
//! 12      J            UTF-8 JSON object, padded with spaces to a multiple of 4 bytes
//! ..      4            P = number of parts (u32)
//! then P parts, each:
//!         4            part id (u32: 0 for a whole mesh, the chunk index for a chunk)
//!         4            V = vertices (u32)
//!         4            T = triangles (u32)
//!         4            flags (u32): bit 0 normals present, bit 1 per-triangle radius ratios present
//!         12 V         positions, f32 x y z
//!         12 V         normals, f32 x y z (bit 0)
//!         12 T         indices, u32 (counter-clockwise, outward)
//!         4 T          radius ratio of each triangle, f32 (bit 1; 0 where undefined)
//! ```
//!
//! Every field is 4 bytes wide and the JSON is padded, so every array starts 4-byte aligned.
//! An empty mesh is a part with `V = T = 0`: for a chunk, "this chunk has no triangles now".

use rmt_mesh::Mesh;

/// The four bytes a reply starts with.
pub const MAGIC: &[u8; 4] = b"RMTS";
/// The format version written by [`encode`].
pub const VERSION: u32 = 1;
/// Flag: the part has normals.
pub const FLAG_NORMALS: u32 = 1;
/// Flag: the part has one radius ratio per triangle.
pub const FLAG_RATIOS: u32 = 2;

/// One mesh of a reply.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Part {
    /// 0 for a whole mesh; the chunk index for a chunk of a sculpted world.
    pub id: u32,
    /// The mesh (normals are sent when `mesh.normals` has one per vertex).
    pub mesh: Mesh,
    /// Per-triangle radius ratios to send (empty: none).
    pub ratios: Vec<f32>,
}

/// Why bytes are not a studio reply.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum WireError {
    /// Too short, wrong magic or version, or counts past the end.
    #[error("not a studio mesh reply: {0}")]
    Malformed(String),
}

/// Bytes [`encode`] writes for `parts` with a JSON header of `json_len` bytes.
pub fn encoded_len(json_len: usize, parts: &[Part]) -> usize {
    let mut n = 12 + json_len.next_multiple_of(4) + 4;
    for p in parts {
        n += 16 + 12 * p.mesh.positions.len() + 4 * p.mesh.indices.len();
        if p.mesh.normals.len() == p.mesh.positions.len() && !p.mesh.normals.is_empty() {
            n += 12 * p.mesh.normals.len();
        }
        if !p.ratios.is_empty() {
            n += 4 * p.ratios.len();
        }
    }
    n
}

/// Writes `header` (a JSON value) and `parts` in the format of the module doc.
pub fn encode(header: &serde_json::Value, parts: &[Part]) -> Vec<u8> {
    let json = header.to_string();
    let mut out = Vec::with_capacity(encoded_len(json.len(), parts));
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    let padded = json.len().next_multiple_of(4);
    out.extend_from_slice(&(padded as u32).to_le_bytes());
    out.extend_from_slice(json.as_bytes());
    out.resize(out.len() + padded - json.len(), b' ');
    out.extend_from_slice(&(parts.len() as u32).to_le_bytes());
    for p in parts {
        let m = &p.mesh;
        let normals = !m.normals.is_empty() && m.normals.len() == m.positions.len();
        let ratios = !p.ratios.is_empty() && p.ratios.len() == m.triangle_count();
        let flags = if normals { FLAG_NORMALS } else { 0 } | if ratios { FLAG_RATIOS } else { 0 };
        for v in [
            p.id,
            m.positions.len() as u32,
            m.triangle_count() as u32,
            flags,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for c in m.positions.iter().flatten() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        if normals {
            for c in m.normals.iter().flatten() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        for &i in &m.indices[..3 * m.triangle_count()] {
            out.extend_from_slice(&i.to_le_bytes());
        }
        if ratios {
            for r in &p.ratios {
                out.extend_from_slice(&r.to_le_bytes());
            }
        }
    }
    out
}

/// Reads a reply written by [`encode`]: the JSON header and the parts (checked: counts within
/// the bytes, indices within the vertices).
pub fn decode(bytes: &[u8]) -> Result<(serde_json::Value, Vec<Part>), WireError> {
    let bad = |m: String| WireError::Malformed(m);
    let mut at = 0usize;
    let word = |at: &mut usize| -> Result<u32, WireError> {
        let b = bytes.get(*at..*at + 4).ok_or_else(|| {
            bad(format!(
                "ends at byte {} inside a 4-byte field",
                bytes.len()
            ))
        })?;
        *at += 4;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if bytes.get(..4) != Some(MAGIC.as_slice()) {
        return Err(bad("wrong magic".into()));
    }
    at += 4;
    let version = word(&mut at)?;
    if version != VERSION {
        return Err(bad(format!("version {version}, expected {VERSION}")));
    }
    let json_len = word(&mut at)? as usize;
    let json = bytes
        .get(at..at.saturating_add(json_len))
        .ok_or_else(|| bad("JSON header past the end".into()))?;
    let header: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| bad(format!("JSON header: {e}")))?;
    at += json_len;
    let count = word(&mut at)?;
    let mut parts = Vec::new();
    for _ in 0..count {
        let id = word(&mut at)?;
        let v = word(&mut at)? as usize;
        let t = word(&mut at)? as usize;
        let flags = word(&mut at)?;
        let need = 12 * v
            + if flags & FLAG_NORMALS != 0 { 12 * v } else { 0 }
            + 12 * t
            + if flags & FLAG_RATIOS != 0 { 4 * t } else { 0 };
        if bytes.len().saturating_sub(at) < need {
            return Err(bad(format!("part {id} needs {need} bytes past the end")));
        }
        let f32s = |n: usize, at: &mut usize| -> Vec<f32> {
            let out = bytes[*at..*at + 4 * n]
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            *at += 4 * n;
            out
        };
        let triples = |f: Vec<f32>| -> Vec<[f32; 3]> {
            f.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        };
        let positions = triples(f32s(3 * v, &mut at));
        let normals = if flags & FLAG_NORMALS != 0 {
            triples(f32s(3 * v, &mut at))
        } else {
            Vec::new()
        };
        let indices: Vec<u32> = f32s(3 * t, &mut at).into_iter().map(f32::to_bits).collect();
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= v) {
            return Err(bad(format!("part {id}: index {i} >= {v} vertices")));
        }
        let ratios = if flags & FLAG_RATIOS != 0 {
            f32s(t, &mut at)
        } else {
            Vec::new()
        };
        parts.push(Part {
            id,
            mesh: Mesh {
                positions,
                normals,
                indices,
            },
            ratios,
        });
    }
    Ok((header, parts))
}

/// The radius ratio `R / (2 r)` of every triangle of `mesh` (1 for equilateral, large for
/// slivers; 0 for zero-area triangles, where it is undefined), as `rmt_mesh::quality` defines it:
/// `abc / (8 (s-a)(s-b)(s-c))` computed as `abc s / (8 A^2)` in f64.
pub fn radius_ratios(mesh: &Mesh) -> Vec<f32> {
    mesh.triangles()
        .map(|t| {
            let p = t.map(|i| {
                mesh.positions
                    .get(i as usize)
                    .map_or(glam::DVec3::NAN, |p| glam::Vec3::from(*p).as_dvec3())
            });
            let (e0, e1, e2) = (p[1] - p[0], p[2] - p[1], p[0] - p[2]);
            let (a, b, c) = (e0.length(), e1.length(), e2.length());
            let area = 0.5 * e0.cross(-e2).length();
            let s = 0.5 * (a + b + c);
            let lmax = a.max(b).max(c);
            if area.partial_cmp(&(rmt_mesh::quality::ZERO_AREA_REL_TOL * lmax * lmax))
                != Some(std::cmp::Ordering::Greater)
            {
                return 0.0;
            }
            (a * b * c * s / (8.0 * area * area)) as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        let mut m = rmt_mesh::solids::tetrahedron();
        m.compute_area_weighted_normals();
        m
    }

    #[test]
    fn round_trip_keeps_header_and_parts_bit_for_bit() {
        let m = tetra();
        let ratios = radius_ratios(&m);
        let parts = vec![
            Part {
                id: 7,
                mesh: m.clone(),
                ratios: ratios.clone(),
            },
            Part {
                id: 9,
                mesh: Mesh::default(),
                ratios: vec![],
            },
        ];
        let header = serde_json::json!({"triangles": 4, "note": "é"});
        let bytes = encode(&header, &parts);
        assert_eq!(bytes.len(), encoded_len(header.to_string().len(), &parts));
        assert_eq!(bytes.len() % 4, 0);
        let (h, back) = decode(&bytes).unwrap();
        assert_eq!(h, header);
        assert_eq!(back, parts);
    }

    #[test]
    fn radius_ratio_is_one_for_equilateral_and_grows_for_slivers() {
        let s = 3f32.sqrt() / 2.0;
        let eq = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, s, 0.0]],
            vec![0, 1, 2],
        );
        assert!((radius_ratios(&eq)[0] - 1.0).abs() < 1e-5);
        let sliver = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.01, 0.0]],
            vec![0, 1, 2],
        );
        assert!(radius_ratios(&sliver)[0] > 10.0);
        let flat = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![0, 1, 2],
        );
        assert_eq!(radius_ratios(&flat)[0], 0.0);
    }

    #[test]
    fn truncated_or_foreign_bytes_are_errors_not_panics() {
        let bytes = encode(
            &serde_json::json!({}),
            &[Part {
                id: 0,
                mesh: tetra(),
                ratios: vec![],
            }],
        );
        for cut in [0, 3, 8, 13, bytes.len() - 1] {
            assert!(decode(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        assert!(decode(b"PLY\nformat").is_err());
        let mut bad_index = bytes.clone();
        let n = bad_index.len();
        bad_index[n - 4..].copy_from_slice(&100u32.to_le_bytes());
        assert!(decode(&bad_index)
            .unwrap_err()
            .to_string()
            .contains("index"));
    }
}
