//! Recording ([`Extractor::set_recording`]): the anchor cell of every output triangle and the
//! clustering's activity, without changing the mesh.

use glam::Vec3;
use rmt_extract::{CellRange, Clustering, ExtractSettings, Extractor, Grid, Lattice};
use rmt_fields::{RandomField, ScalarField, Sphere};
use rmt_mesh::Mesh;

const LATTICES: [Lattice; 2] = [Lattice::BodyCentred, Lattice::Simple];

/// The modes that record anchor cells: marching tetrahedra with integrated clustering (checked
/// or not) or none.
const RECORDING: [Clustering; 3] = [
    Clustering::Integrated,
    Clustering::IntegratedUnchecked,
    Clustering::None,
];

/// Extracts `field` with `settings`, recording or not: the mesh, the anchor cells, the activity.
fn extract(
    field: &dyn ScalarField,
    settings: &ExtractSettings,
    record: bool,
) -> (Mesh, Vec<u32>, Vec<[i32; 3]>) {
    let mut ex = Extractor::new();
    ex.set_recording(record);
    let mut mesh = Mesh::default();
    ex.extract(field, settings, &mut mesh)
        .expect("extraction runs");
    (mesh, ex.triangle_cells().to_vec(), ex.activity().to_vec())
}

/// The triangles of `mesh` as their corner positions, in order.
fn corners(mesh: &Mesh) -> Vec<[[f32; 3]; 3]> {
    mesh.indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|i| mesh.positions[t[i] as usize]))
        .collect()
}

/// Random fields of the property tests on 12^3 cells of [-1, 1]^3.
fn fields() -> Vec<RandomField> {
    (0..24).map(RandomField::from_seed).collect()
}

#[test]
fn recording_leaves_the_mesh_as_it_is() {
    for clustering in RECORDING {
        for lattice in LATTICES {
            for f in fields() {
                let s = ExtractSettings::new(Grid::cube(12, 1.0), lattice, clustering);
                let (plain, cells, _) = extract(&f, &s, false);
                assert!(cells.is_empty(), "nothing is recorded unless asked");
                let (recorded, cells, _) = extract(&f, &s, true);
                let what = format!("{clustering:?} {lattice:?} {f:?}");
                assert_eq!(plain.positions, recorded.positions, "{what}");
                assert_eq!(plain.indices, recorded.indices, "{what}");
                assert_eq!(cells.len(), recorded.triangle_count(), "{what}");
            }
        }
    }
}

/// The triangles recorded in the cells of a box are, in order, those an extraction keeping only
/// that box's cells emits: the recorded cell is the anchor `keep_cells` filters on.
#[test]
fn recorded_cells_are_the_anchors_that_keep_cells_selects() {
    let n = 12;
    let boxes = [
        CellRange {
            lo: [0, 0, 0],
            hi: [5, 12, 12],
        },
        CellRange {
            lo: [3, 4, 5],
            hi: [9, 8, 12],
        },
        CellRange {
            lo: [6, 0, 2],
            hi: [12, 7, 7],
        },
    ];
    let mut checked = 0;
    for (lattice, clustering) in LATTICES.into_iter().flat_map(|l| RECORDING.map(|c| (l, c))) {
        for f in fields().into_iter().take(8) {
            let s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
            let (mesh, cells, _) = extract(&f, &s, true);
            let all = corners(&mesh);
            for r in boxes {
                let inside = |c: u32| {
                    let c = c as usize;
                    r.contains([c % n, (c / n) % n, c / (n * n)])
                };
                let want: Vec<_> = all
                    .iter()
                    .zip(&cells)
                    .filter(|&(_, &c)| inside(c))
                    .map(|(t, _)| *t)
                    .collect();
                let mut k = s;
                k.keep_cells = Some(r);
                let (kept, kept_cells, _) = extract(&f, &k, true);
                assert_eq!(
                    corners(&kept),
                    want,
                    "{clustering:?} {lattice:?} {r:?} {f:?}"
                );
                assert!(kept_cells.iter().all(|&c| inside(c)));
                checked += want.len();
            }
        }
    }
    assert!(checked > 3000, "the boxes hold triangles: {checked}");
}

/// A sphere's proposals all pass at once (no activity); fields where groups fail, lone crossings
/// wait or slivers pair have some, inside the grid, the same for any thread count.
#[test]
fn activity_is_where_clustering_worked_and_does_not_depend_on_threads() {
    let sphere = Sphere::new(Vec3::ZERO, 0.6);
    for lattice in LATTICES {
        let s = ExtractSettings::new(Grid::cube(24, 1.0), lattice, Clustering::Integrated);
        let (_, _, activity) = extract(&sphere, &s, true);
        assert!(activity.is_empty(), "{lattice:?}: {activity:?}");
    }
    let mut active = 0;
    for lattice in LATTICES {
        for f in fields() {
            let mut s = ExtractSettings::new(Grid::cube(12, 1.0), lattice, Clustering::Integrated);
            let (_, _, one) = extract(&f, &s, true);
            s.threads = 2;
            let (_, _, two) = extract(&f, &s, true);
            assert_eq!(one, two, "{lattice:?} {f:?}");
            // Lattice coordinates: cells on the simple lattice, half cells (with the ghost
            // planes at -1 and 2n + 1) on the body-centred one.
            let max = match lattice {
                Lattice::BodyCentred => 25,
                Lattice::Simple => 12,
            };
            let min = if lattice == Lattice::BodyCentred {
                -1
            } else {
                0
            };
            assert!(one.iter().flatten().all(|&c| (min..=max).contains(&c)));
            assert!(one.windows(2).all(|w| w[0] < w[1]), "sorted, each once");
            active += usize::from(!one.is_empty());
        }
    }
    assert!(active > 0, "some random field keeps its clustering busy");
    // Integrated-unchecked keeps its proposals and plain MT has none: anchor cells, no
    // activity. Post-processes change the triangles afterwards: nothing is recorded.
    for (clustering, records_cells) in [
        (Clustering::IntegratedUnchecked, true),
        (Clustering::None, true),
        (Clustering::Postprocessed, false),
    ] {
        for f in fields() {
            let s = ExtractSettings::new(Grid::cube(12, 1.0), Lattice::BodyCentred, clustering);
            let (mesh, cells, activity) = extract(&f, &s, true);
            let want = if records_cells {
                mesh.triangle_count()
            } else {
                0
            };
            assert_eq!(cells.len(), want, "{clustering:?} {f:?}");
            assert!(activity.is_empty(), "{clustering:?} {f:?}");
        }
    }
}

/// With post-processed clustering, recording logs edge collapse's candidates: one `Collapsed`
/// entry per collapse counted, whose two ends ended in one output vertex; every other entry
/// joins two output vertices, or an end that no triangle uses any more. The mesh does not
/// depend on it, and the other modes log nothing.
#[test]
fn post_processing_logs_every_candidate_edge() {
    use rmt_extract::CollapseOutcome;
    for lattice in LATTICES {
        let sphere = Sphere::new(Vec3::new(0.03, -0.02, 0.01), 0.7);
        let s = ExtractSettings::new(Grid::cube(16, 1.0), lattice, Clustering::Postprocessed);
        let mut ex = Extractor::new();
        ex.set_recording(true);
        let mut mesh = Mesh::default();
        let stats = ex.extract(&sphere, &s, &mut mesh).expect("extraction runs");
        let log = ex.collapse_log().to_vec();
        let collapsed: Vec<_> = log
            .iter()
            .filter(|a| a.outcome == CollapseOutcome::Collapsed)
            .collect();
        assert!(stats.collapses > 0, "{lattice:?}");
        assert_eq!(collapsed.len(), stats.collapses, "{lattice:?}");
        let n = mesh.vertex_count() as u32;
        for a in &log {
            if a.outcome == CollapseOutcome::Collapsed {
                assert_eq!(a.ends[0], a.ends[1], "{lattice:?} {a:?}");
            }
            assert!(
                a.ends.iter().all(|&v| v < n || v == u32::MAX),
                "{lattice:?} {a:?}"
            );
        }
        let (plain, _, _) = extract(&sphere, &s, false);
        assert_eq!(corners(&plain), corners(&mesh), "{lattice:?}");
        for clustering in RECORDING {
            let s = ExtractSettings::new(Grid::cube(16, 1.0), lattice, clustering);
            ex.extract(&sphere, &s, &mut mesh).expect("extraction runs");
            assert!(ex.collapse_log().is_empty(), "{clustering:?}");
        }
    }
}
