//! Why a field could not be built.

use std::fmt;
use std::path::PathBuf;

/// Why a field could not be built from its inputs (a mesh, parameters).
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    /// The triangle mesh given to [`crate::MeshSdf`] is unusable as a solid.
    #[error("mesh {source_name}: {problem}")]
    InvalidMesh {
        /// Where the mesh came from: its file path when known, else `"(in memory)"`.
        source_name: MeshSource,
        /// What is wrong with it.
        problem: MeshProblem,
    },
    /// A parameter is out of range (non-finite bounds, margin outside `[0, 0.5)`, ...).
    #[error("invalid parameter {name}: {message}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong and what was given.
        message: String,
    },
}

impl FieldError {
    /// Attaches the file a mesh was read from, so the message names it.
    pub fn with_path(self, path: impl Into<PathBuf>) -> Self {
        match self {
            FieldError::InvalidMesh { problem, .. } => FieldError::InvalidMesh {
                source_name: MeshSource(Some(path.into())),
                problem,
            },
            other => other,
        }
    }
}

/// The origin of a mesh in error messages: a file path, or none for meshes built in memory.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshSource(pub Option<PathBuf>);

impl fmt::Display for MeshSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Some(p) => write!(f, "{}", p.display()),
            None => f.write_str("(in memory)"),
        }
    }
}

/// What makes a triangle mesh unusable for a signed distance field (which needs a closed,
/// manifold, consistently oriented surface bounding a solid).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshProblem {
    /// No triangles (or no vertices).
    #[error("is empty: {vertices} vertices, {triangles} triangles")]
    Empty {
        /// Vertex count.
        vertices: usize,
        /// Triangle count.
        triangles: usize,
    },
    /// The index list is not a whole number of triangles.
    #[error("has {0} indices, not a multiple of 3")]
    RaggedIndices(usize),
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices"
    )]
    IndexOutOfRange {
        /// The triangle (0-based).
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}")]
    NonFiniteVertex {
        /// The vertex (0-based).
        vertex: usize,
        /// Its position.
        position: [f32; 3],
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} is degenerate: it uses vertex {vertex} twice")]
    DegenerateTriangle {
        /// The triangle (0-based).
        triangle: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// Edges with a single triangle: the surface has holes and bounds no solid.
    #[error("is open: {count} boundary edges (e.g. between vertices {example:?}); a signed distance needs a closed surface")]
    Open {
        /// Number of boundary edges.
        count: usize,
        /// One of them (vertex indices, 0-based).
        example: [u32; 2],
    },
    /// Edges with more than two triangles.
    #[error("is not manifold: {count} edges have more than two triangles (e.g. between vertices {example:?})")]
    NonManifoldEdges {
        /// Number of such edges.
        count: usize,
        /// One of them (vertex indices, 0-based).
        example: [u32; 2],
    },
    /// Vertices whose triangles form more than one fan (surfaces touching at a point).
    #[error("is not manifold: {count} vertices join separate sheets of triangles (e.g. vertex {example})")]
    NonManifoldVertices {
        /// Number of such vertices.
        count: usize,
        /// One of them (0-based).
        example: u32,
    },
    /// Neighbouring triangles disagree on which side is outside.
    #[error("is not consistently oriented: {count} edges are traversed in the same direction by both triangles (e.g. between vertices {example:?})")]
    Inconsistent {
        /// Number of such edges.
        count: usize,
        /// One of them (vertex indices, 0-based).
        example: [u32; 2],
    },
}
