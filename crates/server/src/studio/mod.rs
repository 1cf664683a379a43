//! The studio: an interactive page for one extraction at a time (live parameters, flat, smooth
//! and wireframe views, statistics), two configurations side by side (with a blind mode), and
//! sculpting of a chunked terrain; rendered by three.js (vendored in `assets/studio/vendor`) from
//! binary meshes ([`wire`]).
//!
//! | route | what |
//! |---|---|
//! | `GET /studio/` | the page |
//! | `GET /studio/assets/<file>` | its script, style and the vendored three.js (embedded) |
//! | `GET /studio/api/schema` | the parameters the page offers (objects, choices, defaults) |
//! | `GET /studio/api/mesh?<params>[&ratios=1]` | extracts and replies a [`wire`] mesh (one part; with per-triangle radius ratios when asked) and the statistics in its JSON header |
//! | `GET /studio/api/export?format=ply\|obj\|glb&<params>` | the same mesh as a file |
//! | `POST /studio/api/sculpt?<params>` | a sculpt session on a chunked terrain: `201`, every chunk as a part, the session id in the header |
//! | `POST /studio/api/sculpt/<id>/brush` `{"centre": [x,y,z], "mode": "add"\|"subtract", "radius_cells": r, "strength": s}` | one stroke: only the re-meshed chunks come back |
//! | `POST /studio/api/sculpt/<id>/undo`, `/redo` | undo or redo the last stroke (`409` when there is none) |
//! | `GET /studio/api/sculpt/<id>/export?format=ply\|obj\|glb` | the sculpted terrain, welded, as a file |
//! | `POST /studio/api/lod?<params>[&viewer=x,y,z]` | a LOD session ([`lod`]): a multiresolution world meshed for the viewer, `201`, every chunk as a part with its level in the header |
//! | `POST /studio/api/lod/<id>/viewer` `{"viewer": [x,y,z]}` | the viewer moved: only the chunks re-meshed come back, with the ids of those dropped |
//! | `POST /studio/api/lod/<id>/brush` (the sculpt brush's body) | a stroke at any distance: the chunks of every level that see it come back |
//! | `GET /studio/api/lod/<id>/export?format=ply\|obj\|glb` | the LOD world, welded, as a file |
//!
//! `<params>` are the options of `experiments extract` without the dashes (`object=gyroid&
//! resolution=64&clustering=none`); what they mean, which are allowed and how they are checked is
//! the [`Backend`]'s business (the `experiments` binary passes one that parses them with the
//! command line's own parser and checks), so the page and the command line refuse the same
//! things with the same messages. Errors are `{"error": "..."}` with a 4xx status; a request
//! never panics the server (extraction runs on a blocking thread, and a panic there becomes a
//! 500 for that request only).

pub mod lod;
pub mod sculpt;
pub mod wire;

use std::sync::{Arc, Mutex, OnceLock};

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Path, RawQuery, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use axum::Router;
use rmt_mesh::Mesh;
use rmt_terrain::World;
use serde_json::{json, Value};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use crate::http::{asset, json_body, random_token, ApiError};
use lod::{LodField, LodOutcome, LodSession, ViewerRequest};
use sculpt::{BrushRequest, EditOutcome, Session, Sessions};
use wire::Part;

/// Largest request body (brush strokes are a few dozen bytes).
pub const BODY_LIMIT: usize = 16 * 1024;
/// Sculpt sessions kept at once (the least recently used one is dropped first).
pub const MAX_SESSIONS: usize = 4;

/// Request parameters: `(name, value)` pairs of the query string, in order.
pub type Params = Vec<(String, String)>;

/// Why the backend refused or failed a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BackendError {
    /// Bad parameters or sizes over the memory estimate (the message names what): `400`.
    Invalid(String),
    /// The extraction itself failed: `500` (message logged, and sent).
    Failed(String),
}

/// An extracted mesh and its statistics.
pub struct Extracted {
    /// The mesh, world coordinates.
    pub mesh: Mesh,
    /// What the page shows: a JSON object (see the `experiments` backend for its keys).
    pub summary: Value,
}

/// What the studio needs from the application: the parameters, the extraction and the sculpt
/// world, so that the server crate stays free of the object catalogue and of the command line.
pub trait Backend: Send + Sync + 'static {
    /// The parameters the page offers: a JSON object (objects, choices, defaults).
    fn schema(&self) -> Value;
    /// Checks `params` and extracts the mesh they describe.
    fn extract(&self, params: &Params) -> Result<Extracted, BackendError>;
    /// Checks `params` and builds the sculpt world they describe (not meshed yet), with a JSON
    /// description for the page.
    fn world(&self, params: &Params) -> Result<(World, Value), BackendError>;
    /// Checks `params` and builds the multiresolution world they describe (not meshed yet):
    /// the world, a JSON description for the page, and where the viewer starts. By default the
    /// studio has no LOD mode.
    fn lod_world(&self, params: &Params) -> Result<LodBuilt, BackendError> {
        let _ = params;
        Err(BackendError::Invalid("this studio has no LOD mode".into()))
    }
}

/// A multiresolution world built by [`Backend::lod_world`].
pub struct LodBuilt {
    /// The world, not meshed yet.
    pub world: rmt_terrain::lod::LodWorld<LodField>,
    /// What the page shows about it (a JSON object).
    pub description: Value,
    /// The viewer's starting position, world coordinates.
    pub viewer: glam::Vec3,
}

/// The studio's state: the backend, the sculpt sessions (each behind its own lock, so strokes
/// on different sessions run side by side), and the extraction slots: as many extractions (and
/// sculpt worlds being built) run at once as the machine has cores; more wait for a slot.
pub struct Studio {
    backend: Box<dyn Backend>,
    sessions: Mutex<Sessions>,
    lod_sessions: Mutex<Sessions<LodSession>>,
    slots: Arc<Semaphore>,
}

impl Studio {
    /// A studio on `backend`, with one extraction slot per core.
    pub fn new(backend: impl Backend) -> Self {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        Self::with_slots(backend, cores)
    }

    /// A studio on `backend` running at most `slots` extractions at once.
    pub fn with_slots(backend: impl Backend, slots: usize) -> Self {
        Self {
            backend: Box::new(backend),
            sessions: Mutex::new(Sessions::new(MAX_SESSIONS)),
            lod_sessions: Mutex::new(Sessions::new(MAX_SESSIONS)),
            slots: Arc::new(Semaphore::new(slots.max(1))),
        }
    }

    /// Waits for an extraction slot.
    async fn slot(&self) -> Result<OwnedSemaphorePermit, ApiError> {
        self.slots
            .clone()
            .acquire_owned()
            .await
            .map_err(ApiError::internal)
    }
}

const INDEX_HTML: &[u8] = include_bytes!("../../assets/studio/index.html");
const STUDIO_JS: &[u8] = include_bytes!("../../assets/studio/studio.js");
const STUDIO_CSS: &[u8] = include_bytes!("../../assets/studio/studio.css");
const THREE_MODULE: &[u8] = include_bytes!("../../assets/studio/vendor/three/three.module.min.js");
const THREE_CORE: &[u8] = include_bytes!("../../assets/studio/vendor/three/three.core.min.js");
const ORBIT_CONTROLS: &str = include_str!("../../assets/studio/vendor/three/OrbitControls.js");

/// The vendored OrbitControls imports the bare name `three` (resolved by an import map in the
/// three.js examples); the page's content security policy allows no inline script, so the
/// studio serves it with that one import pointed at the module file beside it.
fn orbit_controls() -> &'static [u8] {
    static PATCHED: OnceLock<String> = OnceLock::new();
    PATCHED
        .get_or_init(|| ORBIT_CONTROLS.replace("from 'three';", "from './three.module.min.js';"))
        .as_bytes()
}

/// The studio's routes (all under `/studio/`), to merge into a server's router.
pub fn router(studio: Arc<Studio>) -> Router {
    Router::new()
        .route("/studio", get(|| async { Redirect::permanent("/studio/") }))
        .route(
            "/studio/",
            get(|| async { asset("text/html; charset=utf-8", INDEX_HTML) }),
        )
        .route("/studio/assets/{file}", get(studio_asset))
        .route("/studio/api/schema", get(schema))
        .route("/studio/api/mesh", get(mesh))
        .route("/studio/api/export", get(export))
        .route("/studio/api/sculpt", post(sculpt_new))
        .route("/studio/api/sculpt/{id}/brush", post(sculpt_brush))
        .route("/studio/api/sculpt/{id}/undo", post(sculpt_undo))
        .route("/studio/api/sculpt/{id}/redo", post(sculpt_redo))
        .route("/studio/api/sculpt/{id}/export", get(sculpt_export))
        .route("/studio/api/lod", post(lod_new))
        .route("/studio/api/lod/{id}/viewer", post(lod_viewer))
        .route("/studio/api/lod/{id}/brush", post(lod_brush))
        .route("/studio/api/lod/{id}/export", get(lod_export))
        .layer(DefaultBodyLimit::max(BODY_LIMIT))
        .with_state(studio)
}

/// [`router`] plus `/` redirecting to the studio and `/healthz`: what `experiments studio`
/// serves.
pub fn standalone_router(studio: Arc<Studio>) -> Router {
    router(studio)
        .route("/", get(|| async { Redirect::temporary("/studio/") }))
        .route("/healthz", get(|| async { "ok" }))
}

async fn studio_asset(Path(file): Path<String>) -> Response {
    let js = "text/javascript; charset=utf-8";
    match file.as_str() {
        "studio.js" => asset(js, STUDIO_JS),
        "studio.css" => asset("text/css; charset=utf-8", STUDIO_CSS),
        "three.module.min.js" => asset(js, THREE_MODULE),
        "three.core.min.js" => asset(js, THREE_CORE),
        "OrbitControls.js" => asset(js, orbit_controls()),
        _ => ApiError::not_found(format!("no asset {file}")).into_response(),
    }
}

fn backend_error(e: BackendError) -> ApiError {
    match e {
        BackendError::Invalid(m) => ApiError::bad_request(m),
        BackendError::Failed(m) => {
            eprintln!("studio: extraction failed: {m}");
            ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, m)
        }
    }
}

/// Parses a query string into pairs (`+` and `%XX` decoded); a malformed one is a 400.
pub fn parse_query(query: Option<&str>) -> Result<Params, ApiError> {
    let q = query.unwrap_or("");
    serde_urlencoded_pairs(q).map_err(|e| ApiError::bad_request(format!("bad query string: {e}")))
}

fn serde_urlencoded_pairs(q: &str) -> Result<Params, String> {
    let mut out = Vec::new();
    for pair in q.split('&').filter(|p| !p.is_empty()) {
        let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
        out.push((percent_decode(k)?, percent_decode(v)?));
    }
    Ok(out)
}

fn percent_decode(s: &str) -> Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' => {
                let hex = b
                    .get(i + 1..i + 3)
                    .and_then(|h| std::str::from_utf8(h).ok())
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                    .ok_or_else(|| format!("bad percent escape in `{s}`"))?;
                out.push(hex);
                i += 2;
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8(out).map_err(|_| format!("`{s}` is not UTF-8"))
}

/// Takes the studio's own switches (`name`) out of `params`: `Some(value)` when present.
fn take(params: &mut Params, name: &str) -> Option<String> {
    let at = params.iter().position(|(k, _)| k == name)?;
    Some(params.remove(at).1)
}

/// Runs `f` on a blocking thread; a panic in it becomes a 500 for this request only.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .unwrap_or_else(|e| Err(ApiError::internal(format!("studio worker failed: {e}"))))
}

fn binary_reply(status: StatusCode, bytes: Vec<u8>) -> Response {
    let mut r = (status, bytes).into_response();
    let h = r.headers_mut();
    h.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

async fn schema(State(studio): State<Arc<Studio>>) -> Response {
    crate::http::json_reply(StatusCode::OK, &studio.backend.schema())
}

fn extract(studio: &Studio, params: &Params) -> Result<Extracted, ApiError> {
    studio.backend.extract(params).map_err(backend_error)
}

async fn mesh(State(studio): State<Arc<Studio>>, RawQuery(q): RawQuery) -> Response {
    let run = async move {
        let mut params = parse_query(q.as_deref())?;
        let ratios = match take(&mut params, "ratios").as_deref() {
            None | Some("0") => false,
            Some("1") => true,
            Some(other) => {
                return Err(ApiError::bad_request(format!(
                    "ratios must be 0 or 1, got `{other}`"
                )))
            }
        };
        let slot = studio.slot().await?;
        blocking(move || {
            let _slot = slot;
            let start = std::time::Instant::now();
            let Extracted { mesh, mut summary } = extract(&studio, &params)?;
            let ratios = if ratios {
                wire::radius_ratios(&mesh)
            } else {
                Vec::new()
            };
            if let Value::Object(m) = &mut summary {
                m.insert(
                    "server_ms".into(),
                    json!(start.elapsed().as_secs_f64() * 1e3),
                );
            }
            let parts = [Part {
                id: 0,
                mesh,
                ratios,
            }];
            Ok(wire::encode(&summary, &parts))
        })
        .await
    };
    match run.await {
        Ok(bytes) => binary_reply(StatusCode::OK, bytes),
        Err(e) => e.into_response(),
    }
}

/// A mesh as a file of `format` (`ply` binary, `obj`, `glb`): bytes, content type, extension.
pub fn export_file(mesh: &Mesh, format: &str) -> Result<(Vec<u8>, &'static str), ApiError> {
    let mut out = Vec::new();
    let io = |e: std::io::Error| ApiError::internal(e);
    match format {
        "ply" => {
            rmt_mesh::io::write_ply_binary(&mut out, mesh).map_err(io)?;
            Ok((out, "application/octet-stream"))
        }
        "obj" => {
            rmt_mesh::io::write_obj(&mut out, mesh).map_err(io)?;
            Ok((out, "text/plain; charset=utf-8"))
        }
        "glb" => Ok((
            rmt_mesh::glb::to_glb(mesh).map_err(ApiError::internal)?,
            "model/gltf-binary",
        )),
        other => Err(ApiError::bad_request(format!(
            "unknown export format `{other}` (expected ply, obj or glb)"
        ))),
    }
}

fn file_reply(bytes: Vec<u8>, content_type: &'static str, name: &str) -> Response {
    let mut r = (StatusCode::OK, bytes).into_response();
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
        h.insert(header::CONTENT_DISPOSITION, v);
    }
    r
}

fn export_format(params: &mut Params) -> Result<String, ApiError> {
    let format = take(params, "format").unwrap_or_else(|| "ply".into());
    match format.as_str() {
        "ply" | "obj" | "glb" => Ok(format),
        other => Err(ApiError::bad_request(format!(
            "unknown export format `{other}` (expected ply, obj or glb)"
        ))),
    }
}

async fn export(State(studio): State<Arc<Studio>>, RawQuery(q): RawQuery) -> Response {
    let run = async move {
        let mut params = parse_query(q.as_deref())?;
        let format = export_format(&mut params)?;
        let slot = studio.slot().await?;
        blocking(move || {
            let _slot = slot;
            let Extracted { mesh, summary } = extract(&studio, &params)?;
            let (bytes, ct) = export_file(&mesh, &format)?;
            let object = summary
                .get("object")
                .and_then(Value::as_str)
                .unwrap_or("mesh");
            Ok(file_reply(bytes, ct, &format!("{object}.{format}")))
        })
        .await
    };
    run.await.unwrap_or_else(IntoResponse::into_response)
}

fn sculpt_header(id: &str, s: &Session, outcome: Option<&EditOutcome>) -> Value {
    let (undo, redo) = s.history();
    let mut h = json!({
        "session": id,
        "chunk_count": s.world().chunk_count(),
        "chunk_counts": s.world().chunk_counts(),
        "h": s.world().settings().h,
        "triangles": s.triangles(),
        "undo": undo,
        "redo": redo,
        "world": s.description,
    });
    if let (Some(o), Value::Object(m)) = (outcome, &mut h) {
        m.insert("chunks_remeshed".into(), json!(o.parts.len()));
        m.insert(
            "chunk_ids".into(),
            json!(o.parts.iter().map(|p| p.id).collect::<Vec<_>>()),
        );
        m.insert("changed_values".into(), json!(o.changed_values));
        m.insert("server_ms".into(), json!(o.server_ms));
        m.insert("remesh_ms".into(), json!(o.remesh_ms));
    }
    h
}

async fn sculpt_new(State(studio): State<Arc<Studio>>, RawQuery(q): RawQuery) -> Response {
    let run = async move {
        let params = parse_query(q.as_deref())?;
        let slot = studio.slot().await?;
        blocking(move || {
            let start = std::time::Instant::now();
            let (world, description) = studio.backend.world(&params).map_err(backend_error)?;
            let session = Session::new(world, description)
                .map_err(|m| backend_error(BackendError::Failed(m)))?;
            drop(slot);
            let id = random_token().map_err(ApiError::internal)?;
            let mut header = sculpt_header(&id, &session, None);
            if let Value::Object(m) = &mut header {
                m.insert(
                    "server_ms".into(),
                    json!(start.elapsed().as_secs_f64() * 1e3),
                );
            }
            let bytes = wire::encode(&header, &session.all_parts());
            studio
                .sessions
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(id, session);
            Ok(binary_reply(StatusCode::CREATED, bytes))
        })
        .await
    };
    run.await.unwrap_or_else(IntoResponse::into_response)
}

#[derive(Clone, Copy)]
enum Edit {
    Undo,
    Redo,
}

async fn sculpt_edit(
    studio: Arc<Studio>,
    id: String,
    brush: Option<BrushRequest>,
    edit: Edit,
) -> Response {
    blocking(move || {
        // The sessions' lock only to find the session; the stroke holds the session's own.
        let session = studio
            .sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&id)
            .ok_or_else(|| {
                ApiError::not_found("no such sculpt session (it may have expired); start a new one")
            })?;
        let mut session = session.lock().unwrap_or_else(|e| e.into_inner());
        let session = &mut *session;
        let outcome = match (&brush, edit) {
            (Some(b), _) => session.stroke(b).map_err(ApiError::bad_request)?,
            (None, Edit::Undo) => session
                .undo()
                .map_err(|m| ApiError::new(StatusCode::CONFLICT, m))?,
            (None, Edit::Redo) => session
                .redo()
                .map_err(|m| ApiError::new(StatusCode::CONFLICT, m))?,
        };
        let header = sculpt_header(&id, session, Some(&outcome));
        Ok(binary_reply(
            StatusCode::OK,
            wire::encode(&header, &outcome.parts),
        ))
    })
    .await
    .unwrap_or_else(IntoResponse::into_response)
}

async fn sculpt_brush(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> Response {
    match json_body::<BrushRequest>(body, BODY_LIMIT) {
        Ok(b) => sculpt_edit(studio, id, Some(b), Edit::Undo).await,
        Err(e) => e.into_response(),
    }
}

async fn sculpt_undo(State(studio): State<Arc<Studio>>, Path(id): Path<String>) -> Response {
    sculpt_edit(studio, id, None, Edit::Undo).await
}

async fn sculpt_redo(State(studio): State<Arc<Studio>>, Path(id): Path<String>) -> Response {
    sculpt_edit(studio, id, None, Edit::Redo).await
}

async fn sculpt_export(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(q): RawQuery,
) -> Response {
    let run = async move {
        let mut params = parse_query(q.as_deref())?;
        let format = export_format(&mut params)?;
        if let Some((k, _)) = params.first() {
            return Err(ApiError::bad_request(format!(
                "unknown parameter `{k}` (expected format)"
            )));
        }
        blocking(move || {
            let session = studio
                .sessions
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .get(&id)
                .ok_or_else(|| ApiError::not_found("no such sculpt session"))?;
            let mesh = session.lock().unwrap_or_else(|e| e.into_inner()).welded();
            let (bytes, ct) = export_file(&mesh, &format)?;
            Ok(file_reply(bytes, ct, &format!("terrain.{format}")))
        })
        .await
    };
    run.await.unwrap_or_else(IntoResponse::into_response)
}

/// `x,y,z` as a finite point, or a 400 naming `name`.
fn parse_point(name: &str, text: &str) -> Result<glam::Vec3, ApiError> {
    let bad = || {
        ApiError::bad_request(format!(
            "{name} must be three finite numbers x,y,z, got `{text}`"
        ))
    };
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(*x, *y, *z)),
        _ => Err(bad()),
    }
}

async fn lod_new(State(studio): State<Arc<Studio>>, RawQuery(q): RawQuery) -> Response {
    let run = async move {
        let mut params = parse_query(q.as_deref())?;
        let viewer = take(&mut params, "viewer")
            .map(|v| parse_point("viewer", &v))
            .transpose()?;
        let slot = studio.slot().await?;
        blocking(move || {
            let start = std::time::Instant::now();
            let built = studio.backend.lod_world(&params).map_err(backend_error)?;
            let (session, outcome) = LodSession::new(
                built.world,
                built.description,
                viewer.unwrap_or(built.viewer),
            )
            .map_err(|m| backend_error(BackendError::Failed(m)))?;
            drop(slot);
            let id = random_token().map_err(ApiError::internal)?;
            let header = session.header(&id, &outcome, start.elapsed().as_secs_f64() * 1e3);
            let bytes = wire::encode(&header, &outcome.parts);
            studio
                .lod_sessions
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(id, session);
            Ok(binary_reply(StatusCode::CREATED, bytes))
        })
        .await
    };
    run.await.unwrap_or_else(IntoResponse::into_response)
}

/// A viewer move or a stroke on LOD session `id`.
enum LodEdit {
    Viewer(ViewerRequest),
    Brush(BrushRequest),
}

async fn lod_edit(studio: Arc<Studio>, id: String, edit: LodEdit) -> Response {
    let slot = match studio.slot().await {
        Ok(s) => s,
        Err(e) => return e.into_response(),
    };
    blocking(move || {
        let _slot = slot;
        let start = std::time::Instant::now();
        let session = studio
            .lod_sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&id)
            .ok_or_else(|| {
                ApiError::not_found("no such LOD session (it may have expired); start a new one")
            })?;
        let mut session = session.lock().unwrap_or_else(|e| e.into_inner());
        let outcome: LodOutcome = match &edit {
            LodEdit::Viewer(v) => session.move_viewer(v),
            LodEdit::Brush(b) => session.stroke(b),
        }
        .map_err(ApiError::bad_request)?;
        let header = session.header(&id, &outcome, start.elapsed().as_secs_f64() * 1e3);
        Ok(binary_reply(
            StatusCode::OK,
            wire::encode(&header, &outcome.parts),
        ))
    })
    .await
    .unwrap_or_else(IntoResponse::into_response)
}

async fn lod_viewer(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> Response {
    match json_body::<ViewerRequest>(body, BODY_LIMIT) {
        Ok(v) => lod_edit(studio, id, LodEdit::Viewer(v)).await,
        Err(e) => e.into_response(),
    }
}

async fn lod_brush(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> Response {
    match json_body::<BrushRequest>(body, BODY_LIMIT) {
        Ok(b) => lod_edit(studio, id, LodEdit::Brush(b)).await,
        Err(e) => e.into_response(),
    }
}

async fn lod_export(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(q): RawQuery,
) -> Response {
    let run = async move {
        let mut params = parse_query(q.as_deref())?;
        let format = export_format(&mut params)?;
        if let Some((k, _)) = params.first() {
            return Err(ApiError::bad_request(format!(
                "unknown parameter `{k}` (expected format)"
            )));
        }
        blocking(move || {
            let session = studio
                .lod_sessions
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .get(&id)
                .ok_or_else(|| ApiError::not_found("no such LOD session"))?;
            let mesh = session.lock().unwrap_or_else(|e| e.into_inner()).welded();
            let (bytes, ct) = export_file(&mesh, &format)?;
            Ok(file_reply(bytes, ct, &format!("lod-world.{format}")))
        })
        .await
    };
    run.await.unwrap_or_else(IntoResponse::into_response)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_parse_as_three_finite_numbers() {
        assert_eq!(
            parse_point("viewer", "1, -2.5,3").unwrap(),
            glam::Vec3::new(1.0, -2.5, 3.0)
        );
        for bad in ["", "1,2", "1,2,3,4", "1,x,3", "1,inf,3", "NaN,0,0"] {
            assert!(parse_point("viewer", bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn query_strings_decode_and_bad_escapes_are_errors() {
        let p = parse_query(Some(
            "object=gyroid&iso=-0.1&bounds=-1%2C-1%2C-1%2C1%2C1%2C1&a+b=c",
        ))
        .unwrap();
        assert_eq!(p[0], ("object".into(), "gyroid".into()));
        assert_eq!(p[1].1, "-0.1");
        assert_eq!(p[2].1, "-1,-1,-1,1,1,1");
        assert_eq!(p[3].0, "a b");
        assert!(parse_query(Some("x=%G1")).is_err());
        assert!(parse_query(Some("x=%")).is_err());
        assert!(parse_query(Some("x=%FF")).is_err());
        assert!(parse_query(None).unwrap().is_empty());
    }

    #[test]
    fn the_orbit_controls_import_the_vendored_module() {
        let s = std::str::from_utf8(orbit_controls()).unwrap();
        assert!(s.contains("from './three.module.min.js';"));
        assert!(!s.contains("from 'three';"));
    }
}
