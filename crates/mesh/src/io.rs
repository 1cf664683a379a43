//! PLY, OBJ and binary glTF (`.glb`, through [`crate::glb`]) input and output.
//!
//! Writers take any [`Write`] (they buffer internally) and produce deterministic bytes:
//!
//! - PLY, `binary_little_endian 1.0` or `ascii 1.0`: element `vertex` with `float x y z` and, when
//!   the mesh has normals, `float nx ny nz`; element `face` with `list uchar uint vertex_indices`.
//! - OBJ: `v x y z`, `vn x y z` when the mesh has normals, and `f a b c` (or `f a//a b//b c//c`
//!   with normals), 1-based.
//!
//! ASCII numbers are written with Rust's shortest round-trip formatting, so reading a file back
//! gives the same `f32` values bit for bit. [`save_ply`] and [`save_obj`] write to a temporary
//! file in the target's folder and rename it into place, so a reader never sees a half-written
//! mesh (the rename is atomic; the data is not fsynced, so this does not guard against power
//! loss).
//!
//! Readers: [`read_ply`] reads ASCII and binary (either endianness) PLY files with a `vertex`
//! element (`x y z`, optional `nx ny nz`, other properties skipped) and a `face` element with a
//! `vertex_indices` (or `vertex_index`) list of any integer type; polygons are split into
//! triangle fans and other elements are skipped. [`read_obj`] uses `tobj` (triangulated, single
//! index: a vertex is a distinct position/normal/texture index combination, numbered in order of
//! first use; all objects merged). Every error names the file.
//!
//! ```
//! use rmt_mesh::{io, Mesh};
//! let mesh = Mesh::from_triangles(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
//!     vec![0, 1, 2],
//! );
//! let mut bytes = Vec::new();
//! io::write_ply_ascii(&mut bytes, &mesh).unwrap();
//! assert!(String::from_utf8(bytes).unwrap().ends_with("3 0 1 2\n"));
//! ```

use crate::{check_writable, Mesh};
use std::fs::{self, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why a mesh could not be read or written. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    /// The file could not be opened or read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The file could not be written (or the mesh is not writable: mismatched normals,
    /// out-of-range indices).
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// `tobj` rejected the OBJ file.
    #[error("cannot load OBJ file {}: {source}", path.display())]
    Obj {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: tobj::LoadError,
    },
    /// The file holds no triangles (OBJ only; an empty PLY file is a valid empty mesh).
    #[error("{} holds no triangles", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A face refers to a vertex that does not exist.
    #[error(
        "{}: face {face} refers to vertex {index}, but the file has {vertex_count} vertices",
        path.display()
    )]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// The face (0-based, in file order).
        face: usize,
        /// The offending index (0-based).
        index: i64,
        /// Number of vertices in the file.
        vertex_count: usize,
    },
    /// The PLY file is malformed, truncated or uses something this reader does not support.
    #[error("{}: {message}", path.display())]
    Ply {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the header line or element where it was found.
        message: String,
    },
    /// The binary glTF file could not be written or read.
    #[error("{}: {source}", path.display())]
    Glb {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: crate::glb::GlbError,
    },
    /// The file name's extension is none of `.ply`, `.obj` and `.glb`.
    #[error("{}: unknown mesh format (expected a .ply, .obj or .glb extension)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

fn write_ply_header(
    w: &mut impl Write,
    format: &str,
    mesh: &Mesh,
    normals: bool,
) -> io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(w, "format {format} 1.0")?;
    writeln!(w, "comment written by rmt-mesh")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    for p in ["x", "y", "z"] {
        writeln!(w, "property float {p}")?;
    }
    if normals {
        for p in ["nx", "ny", "nz"] {
            writeln!(w, "property float {p}")?;
        }
    }
    writeln!(w, "element face {}", mesh.triangle_count())?;
    writeln!(w, "property list uchar uint vertex_indices")?;
    writeln!(w, "end_header")
}

/// Writes `mesh` as a `binary_little_endian` PLY file (see the [module documentation](self)).
///
/// Fails with [`io::ErrorKind::InvalidInput`] when the mesh has a normal count other than zero or
/// its vertex count, an index count not a multiple of 3, or an out-of-range index.
pub fn write_ply_binary<W: Write>(out: W, mesh: &Mesh) -> io::Result<()> {
    let normals = check_writable(mesh)?;
    let mut w = BufWriter::with_capacity(1 << 16, out);
    write_ply_header(&mut w, "binary_little_endian", mesh, normals)?;
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p {
            w.write_all(&c.to_le_bytes())?;
        }
        if normals {
            for c in &mesh.normals[i] {
                w.write_all(&c.to_le_bytes())?;
            }
        }
    }
    for t in mesh.triangles() {
        w.write_all(&[3])?;
        for i in t {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    w.flush()
}

/// Writes `mesh` as an `ascii` PLY file (see the [module documentation](self)); fails like
/// [`write_ply_binary`].
pub fn write_ply_ascii<W: Write>(out: W, mesh: &Mesh) -> io::Result<()> {
    let normals = check_writable(mesh)?;
    let mut w = BufWriter::with_capacity(1 << 16, out);
    write_ply_header(&mut w, "ascii", mesh, normals)?;
    for (i, p) in mesh.positions.iter().enumerate() {
        write!(w, "{} {} {}", p[0], p[1], p[2])?;
        if normals {
            let n = mesh.normals[i];
            write!(w, " {} {} {}", n[0], n[1], n[2])?;
        }
        writeln!(w)?;
    }
    for [a, b, c] in mesh.triangles() {
        writeln!(w, "3 {a} {b} {c}")?;
    }
    w.flush()
}

/// Writes `mesh` as an OBJ file (see the [module documentation](self)); fails like
/// [`write_ply_binary`].
pub fn write_obj<W: Write>(out: W, mesh: &Mesh) -> io::Result<()> {
    let normals = check_writable(mesh)?;
    let mut w = BufWriter::with_capacity(1 << 16, out);
    writeln!(w, "# written by rmt-mesh")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    if normals {
        for n in &mesh.normals {
            writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
        }
    }
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if normals {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    w.flush()
}

/// Writes `mesh` to `path` as PLY (binary little-endian when `binary`, else ASCII), atomically:
/// through a temporary file in the same folder, renamed into place.
pub fn save_ply(path: impl AsRef<Path>, mesh: &Mesh, binary: bool) -> Result<(), MeshIoError> {
    save_atomically(path.as_ref(), |file| {
        if binary {
            write_ply_binary(file, mesh)
        } else {
            write_ply_ascii(file, mesh)
        }
    })
}

/// Writes `mesh` to `path` as OBJ, atomically (like [`save_ply`]).
pub fn save_obj(path: impl AsRef<Path>, mesh: &Mesh) -> Result<(), MeshIoError> {
    save_atomically(path.as_ref(), |file| write_obj(file, mesh))
}

/// Writes `mesh` to `path` as binary glTF, atomically (like [`save_ply`]).
pub fn save_glb(path: impl AsRef<Path>, mesh: &Mesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let bytes = crate::glb::to_glb(mesh).map_err(|source| MeshIoError::Glb {
        path: path.to_path_buf(),
        source,
    })?;
    save_atomically(path, |file| file.write_all(&bytes))
}

/// Writes `mesh` to `path` in the format its extension names (any case): `.ply` (binary unless
/// `ascii_ply`), `.obj` or `.glb`; atomically (like [`save_ply`]). Any other extension is
/// [`MeshIoError::UnknownFormat`], and nothing is written.
pub fn save_mesh(path: impl AsRef<Path>, mesh: &Mesh, ascii_ply: bool) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    match extension(path).as_deref() {
        Some("ply") => save_ply(path, mesh, !ascii_ply),
        Some("obj") => save_obj(path, mesh),
        Some("glb") => save_glb(path, mesh),
        _ => Err(MeshIoError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// The lower-case extension of `path`, if any.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Makes temporary names unique between threads of one process (the process id separates
/// processes).
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

fn save_atomically(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> io::Result<()>,
) -> Result<(), MeshIoError> {
    let error = |source| MeshIoError::Write {
        path: path.to_path_buf(),
        source,
    };
    let Some(file_name) = path.file_name() else {
        return Err(error(io::Error::new(
            io::ErrorKind::InvalidInput,
            "path has no file name",
        )));
    };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let temp = folder.join(format!(
        ".{}.{}-{}.tmp",
        file_name.to_string_lossy(),
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .and_then(|mut file| write(&mut file))
        .and_then(|()| fs::rename(&temp, path));
    result.map_err(|e| {
        // Best effort: the temporary file may not exist if creating it failed.
        let _ = fs::remove_file(&temp);
        error(e)
    })
}

/// Reads a mesh from `path`, choosing the format by extension (`.ply`, `.obj` or `.glb`, any
/// case).
pub fn read_mesh(path: impl AsRef<Path>) -> Result<Mesh, MeshIoError> {
    let path = path.as_ref();
    match extension(path).as_deref() {
        Some("ply") => read_ply(path),
        Some("obj") => read_obj(path),
        Some("glb") => read_glb(path),
        _ => Err(MeshIoError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Reads a binary glTF file (see [`crate::glb::from_glb`]); errors name the file.
pub fn read_glb(path: impl AsRef<Path>) -> Result<Mesh, MeshIoError> {
    let path = path.as_ref();
    let bytes = fs::read(path).map_err(|source| MeshIoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    crate::glb::from_glb(&bytes).map_err(|source| MeshIoError::Glb {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads an OBJ file through `tobj`: faces triangulated (fans), one index per vertex (a vertex is
/// a distinct position/texture/normal index combination, numbered in order of first use), all
/// objects merged into one mesh, points and lines ignored, materials ignored. Normals are kept
/// only when every vertex has one.
///
/// Fails, naming the file, when it cannot be read or parsed, when a face index is out of range,
/// or when it holds no triangles.
pub fn read_obj(path: impl AsRef<Path>) -> Result<Mesh, MeshIoError> {
    let path = path.as_ref();
    let bytes = fs::read(path).map_err(|source| MeshIoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    // Triangulated, single index, points and lines discarded.
    let options = tobj::GPU_LOAD_OPTIONS;
    // Materials are not needed: refuse to open them (tobj keeps that error apart).
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|source| MeshIoError::Obj {
        path: path.to_path_buf(),
        source,
    })?;

    let mut mesh = Mesh::default();
    let mut all_have_normals = true;
    for model in &models {
        let m = &model.mesh;
        let offset = mesh.positions.len();
        let count = m.positions.len() / 3;
        let Ok(offset32) = u32::try_from(offset) else {
            return Err(MeshIoError::Obj {
                path: path.to_path_buf(),
                source: tobj::LoadError::GenericFailure,
            });
        };
        for (face, t) in m.indices.chunks_exact(3).enumerate() {
            for &i in t {
                if i as usize >= count {
                    return Err(MeshIoError::IndexOutOfRange {
                        path: path.to_path_buf(),
                        face: mesh.triangle_count() + face,
                        index: i64::from(i),
                        vertex_count: count,
                    });
                }
            }
            mesh.indices.extend(t.iter().map(|&i| i + offset32));
        }
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if m.normals.len() == m.positions.len() && all_have_normals {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(|n| [n[0], n[1], n[2]]));
        } else {
            all_have_normals = false;
        }
    }
    if !all_have_normals {
        mesh.normals.clear();
    }
    if mesh.indices.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(mesh)
}

/// Reads a PLY file: ASCII or binary (little- or big-endian), format version 1.0.
///
/// Needs a `vertex` element with `x y z` properties (`nx ny nz` are read when all three are
/// present; other properties are skipped) and, when there are faces, a `face` element with a
/// `vertex_indices` or `vertex_index` list of an integer type. Faces with more than three
/// vertices become triangle fans; other elements are skipped. A file with vertices and no faces
/// gives a mesh without triangles. Errors name the file and say what is wrong and where
/// (unsupported format, malformed header line, truncated body, out-of-range index).
pub fn read_ply(path: impl AsRef<Path>) -> Result<Mesh, MeshIoError> {
    let path = path.as_ref();
    let bytes = fs::read(path).map_err(|source| MeshIoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let ply_error = |message: String| MeshIoError::Ply {
        path: path.to_path_buf(),
        message,
    };
    let header = parse_ply_header(&bytes).map_err(ply_error)?;
    let body = &bytes[header.body_start..];
    let result = match header.format {
        PlyFormat::Ascii => {
            let text = std::str::from_utf8(body)
                .map_err(|e| ply_error(format!("ASCII body is not text: {e}")))?;
            read_ply_body(&header, &mut AsciiValues::new(text, header.body_line))
        }
        PlyFormat::BinaryLittleEndian => read_ply_body(
            &header,
            &mut BinaryValues {
                bytes: body,
                pos: 0,
                big_endian: false,
            },
        ),
        PlyFormat::BinaryBigEndian => read_ply_body(
            &header,
            &mut BinaryValues {
                bytes: body,
                pos: 0,
                big_endian: true,
            },
        ),
    };
    result.map_err(|e| match e {
        BodyError::Message(message) => ply_error(message),
        BodyError::Index {
            face,
            index,
            vertex_count,
        } => MeshIoError::IndexOutOfRange {
            path: path.to_path_buf(),
            face,
            index,
            vertex_count,
        },
    })
}

/// PLY scalar types, by their size in bytes and interpretation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlyScalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl PlyScalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Debug, PartialEq)]
enum PlyProperty {
    Scalar {
        name: String,
        ty: PlyScalar,
    },
    List {
        name: String,
        count: PlyScalar,
        item: PlyScalar,
    },
}

impl PlyProperty {
    fn name(&self) -> &str {
        match self {
            Self::Scalar { name, .. } | Self::List { name, .. } => name,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
struct PlyElement {
    name: String,
    count: usize,
    properties: Vec<PlyProperty>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlyFormat {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Clone, Debug, PartialEq)]
struct PlyHeader {
    format: PlyFormat,
    elements: Vec<PlyElement>,
    /// Byte offset of the first byte after the `end_header` line.
    body_start: usize,
    /// 1-based line number of the body's first line (for ASCII error messages).
    body_line: usize,
}

/// Parses the header; errors say which line is wrong.
fn parse_ply_header(bytes: &[u8]) -> Result<PlyHeader, String> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(if line_no == 0 {
                "not a PLY file (no header)".to_string()
            } else {
                "header has no end_header line (truncated or not a PLY file)".to_string()
            });
        };
        line_no += 1;
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(format!(
                "header line {line_no} is not text (not a PLY file?)"
            ));
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |what: &str| Err(format!("header line {line_no} ({line:?}): {what}"));
        if line_no == 1 {
            if words != ["ply"] {
                return Err("not a PLY file (first line is not \"ply\")".to_string());
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return bad("unsupported format version (only 1.0)");
                }
                format = Some(match *kind {
                    "ascii" => PlyFormat::Ascii,
                    "binary_little_endian" => PlyFormat::BinaryLittleEndian,
                    "binary_big_endian" => PlyFormat::BinaryBigEndian,
                    _ => return bad("unsupported format"),
                });
            }
            ["element", name, count] => {
                let Ok(count) = count.parse::<usize>() else {
                    return bad("element count is not a non-negative integer");
                };
                elements.push(PlyElement {
                    name: (*name).to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let (Some(count), Some(item)) = (PlyScalar::parse(count), PlyScalar::parse(item))
                else {
                    return bad("unknown property type");
                };
                if !count.is_integer() {
                    return bad("list count type must be an integer type");
                }
                let Some(element) = elements.last_mut() else {
                    return bad("property before any element");
                };
                element.properties.push(PlyProperty::List {
                    name: (*name).to_string(),
                    count,
                    item,
                });
            }
            ["property", ty, name] => {
                let Some(ty) = PlyScalar::parse(ty) else {
                    return bad("unknown property type");
                };
                let Some(element) = elements.last_mut() else {
                    return bad("property before any element");
                };
                element.properties.push(PlyProperty::Scalar {
                    name: (*name).to_string(),
                    ty,
                });
            }
            ["end_header"] => break,
            _ => return bad("not a valid header line"),
        }
    }
    let Some(format) = format else {
        return Err("header has no format line".to_string());
    };
    Ok(PlyHeader {
        format,
        elements,
        body_start: pos,
        body_line: line_no + 1,
    })
}

/// Why the body could not be read (mapped to [`MeshIoError`] by the caller, who knows the path).
enum BodyError {
    Message(String),
    Index {
        face: usize,
        index: i64,
        vertex_count: usize,
    },
}

impl From<String> for BodyError {
    fn from(message: String) -> Self {
        Self::Message(message)
    }
}

/// A stream of property values; one element instance at a time.
trait PlyValues {
    /// Starts element instance `index` of `element`.
    fn begin(&mut self, element: &str, index: usize) -> Result<(), String>;
    /// The next value, of type `ty`.
    fn next(&mut self, ty: PlyScalar) -> Result<f64, String>;
    /// Ends the current element instance.
    fn end(&mut self) -> Result<(), String>;
}

/// ASCII body: one element instance per line.
struct AsciiValues<'a> {
    lines: std::str::Lines<'a>,
    line_no: usize,
    words: std::str::SplitAsciiWhitespace<'a>,
    element: String,
    index: usize,
}

impl<'a> AsciiValues<'a> {
    fn new(text: &'a str, first_line: usize) -> Self {
        Self {
            lines: text.lines(),
            line_no: first_line - 1,
            words: "".split_ascii_whitespace(),
            element: String::new(),
            index: 0,
        }
    }
}

impl PlyValues for AsciiValues<'_> {
    fn begin(&mut self, element: &str, index: usize) -> Result<(), String> {
        loop {
            let Some(line) = self.lines.next() else {
                return Err(format!("truncated: the file ends before {element} {index}"));
            };
            self.line_no += 1;
            if !line.trim().is_empty() {
                self.words = line.split_ascii_whitespace();
                break;
            }
        }
        if self.element != element {
            self.element = element.to_string();
        }
        self.index = index;
        Ok(())
    }

    fn next(&mut self, ty: PlyScalar) -> Result<f64, String> {
        let Some(word) = self.words.next() else {
            return Err(format!(
                "line {}: too few values for {} {}",
                self.line_no, self.element, self.index
            ));
        };
        let value = match ty {
            PlyScalar::F32 => word.parse::<f32>().map(f64::from).ok(),
            PlyScalar::F64 => word.parse::<f64>().ok(),
            _ => word.parse::<i64>().ok().map(|v| v as f64),
        };
        value.ok_or_else(|| {
            format!(
                "line {}: {word:?} is not a valid {ty:?} value",
                self.line_no
            )
        })
    }

    fn end(&mut self) -> Result<(), String> {
        match self.words.next() {
            None => Ok(()),
            Some(word) => Err(format!(
                "line {}: unexpected extra value {word:?} for {} {}",
                self.line_no, self.element, self.index
            )),
        }
    }
}

/// Binary body (either endianness).
struct BinaryValues<'a> {
    bytes: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl BinaryValues<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let chunk = self.bytes.get(self.pos..self.pos + N)?;
        self.pos += N;
        let mut out = [0u8; N];
        out.copy_from_slice(chunk);
        if self.big_endian {
            out.reverse();
        }
        Some(out)
    }
}

impl PlyValues for BinaryValues<'_> {
    fn begin(&mut self, _element: &str, _index: usize) -> Result<(), String> {
        Ok(())
    }

    fn next(&mut self, ty: PlyScalar) -> Result<f64, String> {
        // After `take` the bytes are little-endian whatever the file's order.
        let value = match ty {
            PlyScalar::I8 => self.take::<1>().map(|b| f64::from(i8::from_le_bytes(b))),
            PlyScalar::U8 => self.take::<1>().map(|b| f64::from(b[0])),
            PlyScalar::I16 => self.take().map(|b| f64::from(i16::from_le_bytes(b))),
            PlyScalar::U16 => self.take().map(|b| f64::from(u16::from_le_bytes(b))),
            PlyScalar::I32 => self.take().map(|b| f64::from(i32::from_le_bytes(b))),
            PlyScalar::U32 => self.take().map(|b| f64::from(u32::from_le_bytes(b))),
            PlyScalar::F32 => self.take().map(|b| f64::from(f32::from_le_bytes(b))),
            PlyScalar::F64 => self.take().map(f64::from_le_bytes),
        };
        value.ok_or_else(|| {
            format!(
                "truncated: the file ends at byte {} of the body, inside a {}-byte value",
                self.bytes.len(),
                ty.size()
            )
        })
    }

    fn end(&mut self) -> Result<(), String> {
        Ok(())
    }
}

/// Reads every element of the body into a mesh.
fn read_ply_body(header: &PlyHeader, values: &mut impl PlyValues) -> Result<Mesh, BodyError> {
    let Some(vertex_element) = header.elements.iter().find(|e| e.name == "vertex") else {
        return Err("no \"vertex\" element".to_string().into());
    };
    let vertex_count = vertex_element.count;
    if vertex_count > u32::MAX as usize + 1 {
        return Err(format!("{vertex_count} vertices do not fit 32-bit indices").into());
    }
    let scalar_slot = |name: &str| {
        vertex_element
            .properties
            .iter()
            .position(|p| matches!(p, PlyProperty::Scalar { name: n, .. } if n == name))
    };
    let (Some(x), Some(y), Some(z)) = (scalar_slot("x"), scalar_slot("y"), scalar_slot("z")) else {
        return Err("the vertex element lacks a scalar x, y or z property"
            .to_string()
            .into());
    };
    let normal_slots = match (scalar_slot("nx"), scalar_slot("ny"), scalar_slot("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };

    let mut mesh = Mesh::default();
    let mut scalars = Vec::new();
    let mut polygon: Vec<u32> = Vec::new();
    let mut face_index = 0usize;
    for element in &header.elements {
        let index_list = match element.name.as_str() {
            "face" => {
                let slot = element.properties.iter().position(|p| {
                    matches!(p, PlyProperty::List { name, .. }
                        if name == "vertex_indices" || name == "vertex_index")
                });
                if slot.is_none() && element.count > 0 {
                    return Err("the face element has no vertex_indices list"
                        .to_string()
                        .into());
                }
                slot
            }
            _ => None,
        };
        let is_vertex = std::ptr::eq(element, vertex_element);
        if is_vertex {
            // The count comes from the file: do not trust it for the allocation.
            mesh.positions.reserve(vertex_count.min(1 << 20));
        }
        for i in 0..element.count {
            values.begin(&element.name, i)?;
            scalars.clear();
            for (slot, property) in element.properties.iter().enumerate() {
                match *property {
                    PlyProperty::Scalar { ty, .. } => scalars.push(values.next(ty)?),
                    PlyProperty::List { count, item, .. } => {
                        scalars.push(f64::NAN);
                        let n = values.next(count)?;
                        if n < 0.0 {
                            return Err(format!(
                                "{} {i}: negative list length for {}",
                                element.name,
                                property.name()
                            )
                            .into());
                        }
                        let is_index_list = Some(slot) == index_list;
                        if is_index_list {
                            polygon.clear();
                        }
                        for _ in 0..n as u64 {
                            let v = values.next(item)?;
                            if is_index_list {
                                polygon.push(vertex_index(v, face_index, vertex_count)?);
                            }
                        }
                    }
                }
            }
            values.end()?;
            if is_vertex {
                mesh.positions.push([x, y, z].map(|s| scalars[s] as f32));
                if let Some(slots) = normal_slots {
                    mesh.normals.push(slots.map(|s| scalars[s] as f32));
                }
            }
            if index_list.is_some() {
                if polygon.len() < 3 {
                    return Err(format!(
                        "face {face_index} has {} vertices (at least 3 needed)",
                        polygon.len()
                    )
                    .into());
                }
                for k in 1..polygon.len() - 1 {
                    mesh.indices
                        .extend([polygon[0], polygon[k], polygon[k + 1]]);
                }
                face_index += 1;
            }
        }
    }
    Ok(mesh)
}

/// Checks one index read from a face list.
fn vertex_index(value: f64, face: usize, vertex_count: usize) -> Result<u32, BodyError> {
    if value >= 0.0 && value.fract() == 0.0 && value < vertex_count as f64 {
        Ok(value as u32)
    } else if value.fract() == 0.0 && value.is_finite() {
        Err(BodyError::Index {
            face,
            index: value as i64,
            vertex_count,
        })
    } else {
        Err(format!("face {face}: index {value} is not an integer").into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solids::tetrahedron;
    use proptest::prelude::*;

    fn with_normals(mut mesh: Mesh) -> Mesh {
        mesh.compute_area_weighted_normals();
        mesh
    }

    fn write_temp(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.path().join(name);
        if let Err(e) = fs::write(&path, bytes) {
            panic!("cannot write {}: {e}", path.display());
        }
        path
    }

    fn temp_dir() -> tempfile::TempDir {
        match tempfile::tempdir() {
            Ok(d) => d,
            Err(e) => panic!("no temporary folder: {e}"),
        }
    }

    fn ply_bytes(mesh: &Mesh, binary: bool) -> Vec<u8> {
        let mut bytes = Vec::new();
        let result = if binary {
            write_ply_binary(&mut bytes, mesh)
        } else {
            write_ply_ascii(&mut bytes, mesh)
        };
        assert!(result.is_ok(), "{result:?}");
        bytes
    }

    /// Writes, saves and reads back through every format; asserts exact equality for PLY and
    /// equality of the triangles' corner positions (and normals) for OBJ, which renumbers.
    fn assert_round_trips(mesh: &Mesh) {
        let dir = temp_dir();
        for binary in [true, false] {
            let path = dir
                .path()
                .join(if binary { "m_bin.ply" } else { "m_asc.ply" });
            assert!(save_ply(&path, mesh, binary).is_ok());
            match read_ply(&path) {
                Ok(back) => assert_eq!(&back, mesh, "binary = {binary}"),
                Err(e) => panic!("{e}"),
            }
        }
        if mesh.triangle_count() == 0 {
            return;
        }
        let path = dir.path().join("m.obj");
        assert!(save_obj(&path, mesh).is_ok());
        match read_obj(&path) {
            Ok(back) => {
                assert_eq!(back.triangle_count(), mesh.triangle_count());
                assert_eq!(back.normals.is_empty(), mesh.normals.is_empty());
                for (a, b) in mesh.indices.iter().zip(&back.indices) {
                    assert_eq!(mesh.positions[*a as usize], back.positions[*b as usize]);
                    if !mesh.normals.is_empty() {
                        assert_eq!(mesh.normals[*a as usize], back.normals[*b as usize]);
                    }
                }
            }
            Err(e) => panic!("{e}"),
        }
        // No temporary files are left behind.
        let leftovers = fs::read_dir(dir.path())
            .map(|entries| {
                entries
                    .filter_map(Result::ok)
                    .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
                    .count()
            })
            .unwrap_or(usize::MAX);
        assert_eq!(leftovers, 0);
    }

    #[test]
    fn meshes_round_trip_through_every_writer() {
        assert_round_trips(&tetrahedron());
        assert_round_trips(&with_normals(tetrahedron()));
        assert_round_trips(&Mesh::default());
        // Unreferenced vertices survive PLY.
        let mut extra = tetrahedron();
        extra.positions.push([7.5, -1e-30, 3e30]);
        assert_round_trips(&extra);
    }

    #[test]
    fn binary_ply_has_the_documented_layout() {
        let mesh = with_normals(tetrahedron());
        let bytes = ply_bytes(&mesh, true);
        let header = "ply\nformat binary_little_endian 1.0\ncomment written by rmt-mesh\n\
            element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
            property float nx\nproperty float ny\nproperty float nz\nelement face 4\n\
            property list uchar uint vertex_indices\nend_header\n";
        assert!(bytes.starts_with(header.as_bytes()));
        assert_eq!(bytes.len(), header.len() + 4 * 24 + 4 * 13);
        // The last face is (1, 2, 3).
        let tail = &bytes[bytes.len() - 13..];
        assert_eq!(tail[0], 3);
        assert_eq!(&tail[1..5], &1u32.to_le_bytes());
        assert_eq!(&tail[9..13], &3u32.to_le_bytes());
    }

    #[test]
    fn obj_uses_one_based_indices_and_normal_references() {
        let mut bytes = Vec::new();
        assert!(write_obj(&mut bytes, &tetrahedron()).is_ok());
        let text = String::from_utf8(bytes).unwrap_or_default();
        assert!(text.lines().any(|l| l == "f 1 3 2"), "{text}");
        let mut bytes = Vec::new();
        assert!(write_obj(&mut bytes, &with_normals(tetrahedron())).is_ok());
        let text = String::from_utf8(bytes).unwrap_or_default();
        assert!(text.lines().any(|l| l == "f 1//1 3//3 2//2"), "{text}");
        assert_eq!(text.lines().filter(|l| l.starts_with("vn ")).count(), 4);
    }

    #[test]
    fn writers_reject_inconsistent_meshes() {
        let mut mesh = tetrahedron();
        mesh.normals.push([0.0, 0.0, 1.0]);
        assert!(write_ply_binary(Vec::new(), &mesh).is_err());
        let mut mesh = tetrahedron();
        mesh.indices.push(0);
        assert!(write_obj(Vec::new(), &mesh).is_err());
        let mut mesh = tetrahedron();
        mesh.indices[5] = 4;
        assert!(write_ply_ascii(Vec::new(), &mesh).is_err());
        // A failed save leaves neither the target nor a temporary file.
        let dir = temp_dir();
        let path = dir.path().join("bad.ply");
        match save_ply(&path, &mesh, true) {
            Err(e) => assert!(e.to_string().contains("bad.ply"), "{e}"),
            Ok(()) => panic!("saved an invalid mesh"),
        }
        assert_eq!(
            fs::read_dir(dir.path())
                .map(|d| d.count())
                .unwrap_or(usize::MAX),
            0
        );
    }

    #[test]
    fn save_replaces_an_existing_file() {
        let dir = temp_dir();
        let path = dir.path().join("m.ply");
        assert!(save_ply(&path, &tetrahedron(), true).is_ok());
        let mut smaller = tetrahedron();
        smaller.indices.truncate(3);
        assert!(save_ply(&path, &smaller, false).is_ok());
        assert_eq!(read_ply(&path).ok(), Some(smaller));
    }

    #[test]
    fn read_ply_accepts_other_types_polygons_and_extra_elements() {
        // Big-endian, double positions, int indices, a quad, an extra scalar, an extra element.
        let mut bytes = b"ply\r\nformat binary_big_endian 1.0\r\nelement vertex 4\r\n\
            property double x\r\nproperty double y\r\nproperty double z\r\n\
            property uchar red\r\nelement face 1\r\nproperty list uchar int vertex_index\r\n\
            property float quality\r\nelement edge 1\r\nproperty int vertex1\r\n\
            property int vertex2\r\nend_header\r\n"
            .to_vec();
        let corners = [
            [0.0f64, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        for c in corners {
            for v in c {
                bytes.extend(v.to_be_bytes());
            }
            bytes.push(255);
        }
        bytes.push(4);
        for i in [0i32, 1, 2, 3] {
            bytes.extend(i.to_be_bytes());
        }
        bytes.extend(0.5f32.to_be_bytes());
        bytes.extend(0i32.to_be_bytes());
        bytes.extend(1i32.to_be_bytes());
        let dir = temp_dir();
        let path = write_temp(&dir, "quad.ply", &bytes);
        match read_ply(&path) {
            Ok(mesh) => {
                assert_eq!(mesh.indices, vec![0, 1, 2, 0, 2, 3]);
                assert_eq!(mesh.positions[2], [1.0, 1.0, 0.0]);
                assert!(mesh.normals.is_empty());
            }
            Err(e) => panic!("{e}"),
        }
    }

    fn read_ply_error(bytes: &[u8]) -> String {
        let dir = temp_dir();
        let path = write_temp(&dir, "broken.ply", bytes);
        match read_ply(&path) {
            Ok(mesh) => panic!("read a broken file as {mesh:?}"),
            Err(e) => {
                let message = e.to_string();
                assert!(message.contains("broken.ply"), "{message}");
                message
            }
        }
    }

    #[test]
    fn read_ply_errors_name_the_file_and_the_problem() {
        let good = ply_bytes(&tetrahedron(), true);
        let truncated = read_ply_error(&good[..good.len() - 5]);
        assert!(truncated.contains("truncated"), "{truncated}");

        let mut bad_index = ply_bytes(&tetrahedron(), false);
        let n = bad_index.len();
        bad_index.truncate(n - 2);
        bad_index.extend(b"9\n");
        let message = read_ply_error(&bad_index);
        assert!(message.contains("face 3 refers to vertex 9"), "{message}");

        let message = read_ply_error(b"ply\nformat binary_middle_endian 1.0\nend_header\n");
        assert!(message.contains("unsupported format"), "{message}");
        let message = read_ply_error(b"solid cube\nfacet normal 0 0 1\n");
        assert!(message.contains("not a PLY file"), "{message}");
        let message = read_ply_error(b"ply\nformat ascii 1.0\nelement vertex 1\n");
        assert!(message.contains("end_header"), "{message}");
        let message = read_ply_error(
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
        );
        assert!(message.contains("x, y or z"), "{message}");
        let message = read_ply_error(
            b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
              property float z\nend_header\n0 0 0\n1 2\n",
        );
        assert!(
            message.contains("line 9") && message.contains("too few"),
            "{message}"
        );
        let message = read_ply_error(
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
              property float z\nend_header\n0 zero 0\n",
        );
        assert!(message.contains("\"zero\""), "{message}");

        let dir = temp_dir();
        match read_ply(dir.path().join("missing.ply")) {
            Err(MeshIoError::Read { path, .. }) => assert!(path.ends_with("missing.ply")),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn read_obj_merges_objects_triangulates_and_reports_errors() {
        let dir = temp_dir();
        let text = "mtllib missing.mtl\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
            o b\nv 0 0 5\nv 1 0 5\nv 0 1 5\nf 5 6 7\nl 5 6\n";
        let path = write_temp(&dir, "two.obj", text.as_bytes());
        match read_obj(&path) {
            Ok(mesh) => {
                assert_eq!(mesh.triangle_count(), 3);
                assert_eq!(mesh.vertex_count(), 7);
                let r = crate::validate(&mesh, &|_| false);
                assert_eq!((r.components, r.zero_area_triangles), (2, 0));
                assert_eq!(mesh.positions[mesh.indices[6] as usize], [0.0, 0.0, 5.0]);
            }
            Err(e) => panic!("{e}"),
        }

        let path = write_temp(&dir, "range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
        let message = read_obj(&path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(message.contains("range.obj"), "{message}");

        let path = write_temp(&dir, "empty.obj", b"# nothing\nv 0 0 0\n");
        assert!(matches!(read_obj(&path), Err(MeshIoError::Empty { .. })));

        let message = read_obj(dir.path().join("nope.obj"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            message.contains("nope.obj") && message.contains("cannot read"),
            "{message}"
        );

        assert!(matches!(
            read_mesh(dir.path().join("x.stl")),
            Err(MeshIoError::UnknownFormat { .. })
        ));
    }

    fn arbitrary_mesh() -> impl Strategy<Value = Mesh> {
        (1usize..40, any::<bool>()).prop_flat_map(|(n, normals)| {
            let coord = prop_oneof![
                -1e6f32..1e6,
                Just(0.0f32),
                Just(-0.0f32),
                prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL,
            ];
            (
                prop::collection::vec([coord.clone(), coord.clone(), coord.clone()], n),
                prop::collection::vec(
                    [coord.clone(), coord.clone(), coord],
                    if normals { n } else { 0 },
                ),
                prop::collection::vec(0..n as u32, 0..20).prop_map(|mut v| {
                    v.truncate(v.len() / 3 * 3);
                    v
                }),
            )
                .prop_map(|(positions, normals, indices)| Mesh {
                    positions,
                    normals,
                    indices,
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn arbitrary_meshes_round_trip(mesh in arbitrary_mesh()) {
            assert_round_trips(&mesh);
        }

        #[test]
        fn truncated_files_give_errors_not_panics(cut in 0.0f64..1.0, binary in any::<bool>()) {
            let bytes = ply_bytes(&with_normals(tetrahedron()), binary);
            let keep = ((bytes.len() - 1) as f64 * cut) as usize;
            let dir = temp_dir();
            let path = write_temp(&dir, "cut.ply", &bytes[..keep]);
            prop_assert!(read_ply(&path).is_err());
        }
    }
}
