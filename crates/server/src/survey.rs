//! The survey's routes: the participant's page and API, the animations, and the admin page.
//!
//! | route | who | what |
//! |---|---|---|
//! | `GET /` | anyone | the page (intro and consent, then one question per screen) |
//! | `GET /assets/survey.js`, `/assets/survey.css` | anyone | its script and style (embedded) |
//! | `GET /gif/<name>.gif` | anyone | a single turntable of the study, by its anonymous name |
//! | `POST /api/session` `{"consent": true}` | anyone | starts a session: `201` with its view and token |
//! | `GET /api/session` | participant | the session's questions (names only), answers so far, finished |
//! | `POST /api/answer` `{"item": k, "answer": "L"/"N"/"R", "ms": t}` | participant | stores one answer (`201`); a second answer to the same question gets `409` |
//! | `POST /api/finish` | participant | finishes once all are answered; idempotent (`200` again) |
//! | `GET /admin` | admin | live counts (HTML) with export links |
//! | `GET /admin/counts` | admin | live counts (JSON) |
//! | `GET /admin/export/<file>` | admin | an export file (`responses.csv`, ...) |
//! | `GET /healthz` | anyone | `ok` |
//!
//! A participant authenticates with `Authorization: Bearer <token>` (the token of their
//! session, which the page keeps in the browser's storage); the admin with the token printed at
//! start, as `Authorization: Bearer <token>` or `?token=<token>`. Errors are
//! `{"error": "..."}` with a 4xx status, and nothing is stored. Request bodies are limited to
//! [`BODY_LIMIT`] bytes.
//!
//! Blinding: nothing a participant can fetch names a configuration. The page and script are
//! static; the session lists questions by number with the two anonymous animation names (sides
//! already swapped); the animations are served by those names from the run's `render/` folder
//! and nothing else of the run folder is reachable. Every animation is served at the same size
//! ([`pad_gif`]), so sizes do not tell configurations apart either.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Path, RawQuery, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use serde::Deserialize;

use crate::http::{
    asset, bearer, constant_time_eq, is_token_shaped, json_body, json_reply, random_token, ApiError,
};
use crate::store::{Side, Store, StoreError};

/// Largest request body accepted, in bytes.
pub const BODY_LIMIT: usize = 1024;
/// Longest answer time accepted from the page (a day), in milliseconds.
pub const MAX_ANSWER_MS: u64 = 86_400_000;

const INDEX_HTML: &[u8] = include_bytes!("../assets/survey/index.html");
const SURVEY_JS: &[u8] = include_bytes!("../assets/survey/survey.js");
const SURVEY_CSS: &[u8] = include_bytes!("../assets/survey/survey.css");

/// Everything the survey routes share.
pub struct Survey {
    store: Arc<Store>,
    render_dir: PathBuf,
    admin_token: String,
    names: BTreeSet<String>,
    /// The size every animation is served at ([`pad_gif`]): the largest plus [`GIF_PAD_MIN`].
    gif_size: OnceLock<usize>,
}

impl Survey {
    /// A survey over `store`, serving animations from `render_dir` (the run's `render/`),
    /// administered with `admin_token`.
    pub fn new(store: Store, render_dir: PathBuf, admin_token: String) -> Arc<Survey> {
        let names = store.study().shown_names();
        Arc::new(Survey {
            store: Arc::new(store),
            render_dir,
            admin_token,
            names,
            gif_size: OnceLock::new(),
        })
    }

    /// The store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The admin token.
    pub fn admin_token(&self) -> &str {
        &self.admin_token
    }

    /// The size every animation is served at: the largest file of the study plus
    /// [`GIF_PAD_MIN`] (taken at the first request; blocking file system calls).
    pub fn gif_size(&self) -> usize {
        *self.gif_size.get_or_init(|| {
            let largest = self
                .names
                .iter()
                .filter_map(|n| std::fs::metadata(self.render_dir.join(format!("{n}.gif"))).ok())
                .map(|m| usize::try_from(m.len()).unwrap_or(usize::MAX))
                .max()
                .unwrap_or(0);
            largest.saturating_add(GIF_PAD_MIN)
        })
    }
}

/// Bytes [`pad_gif`] adds at least (it cannot add 1, 2 or 4).
pub const GIF_PAD_MIN: usize = 5;

/// Pads a GIF to exactly `size` bytes with one comment extension (sub-blocks of spaces) before
/// its trailer. Decoders skip comments, so the image is unchanged; the survey serves every
/// animation at the same size so that a file's size (about 0.9 MB for one configuration, 1.2 MB
/// for another) tells a participant nothing. `size` must be the GIF's length, or at least
/// [`GIF_PAD_MIN`] more; otherwise, or for bytes that do not end with the GIF trailer, nothing
/// changes and the result is `false`.
pub fn pad_gif(gif: &mut Vec<u8>, size: usize) -> bool {
    if size == gif.len() {
        return true;
    }
    if size < gif.len().saturating_add(GIF_PAD_MIN) || gif.last() != Some(&0x3B) {
        return false;
    }
    // Introducer, label and terminator take 3 bytes; the other m are n sub-blocks, each a length
    // byte and 1 to 255 bytes of data (m >= 2, so n <= m / 2 and every block gets a byte).
    let m = size - gif.len() - 3;
    let n = m.div_ceil(256);
    let data = m - n;
    let mut ext = Vec::with_capacity(m + 3);
    ext.extend_from_slice(&[0x21, 0xFE]);
    for k in 0..n {
        let len = data / n + usize::from(k < data % n);
        ext.push(u8::try_from(len).unwrap_or(u8::MAX));
        ext.resize(ext.len() + len, b' ');
    }
    ext.push(0);
    let trailer = gif.len() - 1;
    gif.splice(trailer..trailer, ext);
    gif.len() == size
}

/// The survey's router.
pub fn router(survey: Arc<Survey>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/assets/survey.js", get(script))
        .route("/assets/survey.css", get(style))
        .route("/healthz", get(|| async { "ok" }))
        .route("/gif/{file}", get(gif))
        .route("/api/session", post(start_session).get(get_session))
        .route("/api/answer", post(post_answer))
        .route("/api/finish", post(post_finish))
        .route("/admin", get(admin_page))
        .route("/admin/counts", get(admin_counts))
        .route("/admin/export/{file}", get(admin_export))
        .fallback(|uri: axum::http::Uri| async move {
            ApiError::not_found(format!("no such page: {}", uri.path()))
        })
        .layer(DefaultBodyLimit::max(BODY_LIMIT))
        .with_state(survey)
}

async fn index() -> Response {
    asset("text/html; charset=utf-8", INDEX_HTML)
}

async fn script() -> Response {
    asset("text/javascript; charset=utf-8", SURVEY_JS)
}

async fn style() -> Response {
    asset("text/css; charset=utf-8", SURVEY_CSS)
}

fn store_error(e: StoreError) -> ApiError {
    match e {
        StoreError::UnknownToken => ApiError::unauthorized(
            "unknown participant token: start a new session from the survey's first page",
        ),
        StoreError::UnknownItem { .. } => ApiError::bad_request(e.to_string()),
        StoreError::AlreadyAnswered { .. }
        | StoreError::Finished
        | StoreError::Unfinished { .. } => ApiError::new(StatusCode::CONFLICT, e.to_string()),
        StoreError::Sqlite { .. } | StoreError::BadDatabase { .. } | StoreError::Io { .. } => {
            ApiError::internal(e)
        }
    }
}

/// Runs a store call off the async threads.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, StoreError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(ApiError::internal)?
        .map_err(store_error)
}

fn participant_token(headers: &HeaderMap) -> Result<String, ApiError> {
    let token = bearer(headers).ok_or_else(|| {
        ApiError::unauthorized("missing participant token (Authorization: Bearer <token>)")
    })?;
    if !is_token_shaped(token) {
        return Err(store_error(StoreError::UnknownToken));
    }
    Ok(token.to_string())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Consent {
    consent: bool,
}

async fn start_session(
    State(survey): State<Arc<Survey>>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let consent: Consent = json_body(body, BODY_LIMIT)?;
    if !consent.consent {
        return Err(ApiError::bad_request(
            "consent is required to take part (send {\"consent\": true})",
        ));
    }
    let token = random_token().map_err(ApiError::internal)?;
    let store = survey.store.clone();
    let view = blocking(move || store.create_session(&token)).await?;
    Ok(json_reply(StatusCode::CREATED, &view))
}

async fn get_session(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let token = participant_token(&headers)?;
    let store = survey.store.clone();
    let view = blocking(move || store.session(&token)).await?;
    Ok(json_reply(StatusCode::OK, &view))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnswerRequest {
    item: u64,
    answer: String,
    #[serde(default)]
    ms: Option<u64>,
}

async fn post_answer(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let token = participant_token(&headers)?;
    let request: AnswerRequest = json_body(body, BODY_LIMIT)?;
    let side = Side::parse(&request.answer).ok_or_else(|| {
        ApiError::bad_request(format!(
            "unknown answer `{}` (expected L, N or R)",
            request.answer
        ))
    })?;
    if request.ms.is_some_and(|ms| ms > MAX_ANSWER_MS) {
        return Err(ApiError::bad_request(format!(
            "answer time {} ms is out of range (0 to {MAX_ANSWER_MS} ms)",
            request.ms.unwrap_or(0)
        )));
    }
    let store = survey.store.clone();
    let ack = blocking(move || store.answer(&token, request.item, side, request.ms)).await?;
    Ok(json_reply(StatusCode::CREATED, &ack))
}

async fn post_finish(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let token = participant_token(&headers)?;
    let store = survey.store.clone();
    let view = blocking(move || store.finish(&token)).await?;
    Ok(json_reply(StatusCode::OK, &view))
}

async fn gif(
    State(survey): State<Arc<Survey>>,
    Path(file): Path<String>,
) -> Result<Response, ApiError> {
    let name = file
        .strip_suffix(".gif")
        .filter(|n| survey.names.contains(*n))
        .ok_or_else(|| ApiError::not_found(format!("no such animation: {file}")))?;
    let path = survey.render_dir.join(format!("{name}.gif"));
    let mut bytes = tokio::fs::read(&path)
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?;
    let size = {
        let survey = survey.clone();
        tokio::task::spawn_blocking(move || survey.gif_size())
            .await
            .map_err(ApiError::internal)?
    };
    if !pad_gif(&mut bytes, size) {
        // Changed on disk since the size was taken, or not a GIF: served as it is.
        eprintln!(
            "{}: {} bytes, not padded to {size} (re-rendered while serving?)",
            path.display(),
            bytes.len()
        );
    }
    let mut response = bytes.into_response();
    let h = response.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static("image/gif"));
    h.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("public, max-age=86400"),
    );
    h.insert(
        "x-content-type-options",
        HeaderValue::from_static("nosniff"),
    );
    Ok(response)
}

/// The admin token from `Authorization: Bearer` or `?token=`.
fn check_admin(
    survey: &Survey,
    headers: &HeaderMap,
    query: &Option<String>,
) -> Result<(), ApiError> {
    let from_query = query.as_deref().and_then(|q| {
        q.split('&')
            .find_map(|pair| pair.strip_prefix("token="))
            .map(str::to_string)
    });
    let given = bearer(headers).map(str::to_string).or(from_query);
    match given {
        Some(token) if constant_time_eq(&token, &survey.admin_token) => Ok(()),
        Some(_) => Err(ApiError::unauthorized("wrong admin token")),
        None => Err(ApiError::unauthorized(
            "admin token required (Authorization: Bearer <token> or ?token=<token>; the server \
             prints it at start)",
        )),
    }
}

async fn admin_counts(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
) -> Result<Response, ApiError> {
    check_admin(&survey, &headers, &query)?;
    let store = survey.store.clone();
    let counts = blocking(move || store.counts()).await?;
    Ok(json_reply(StatusCode::OK, &counts))
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

async fn admin_page(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
) -> Result<Response, ApiError> {
    check_admin(&survey, &headers, &query)?;
    let store = survey.store.clone();
    let counts = blocking(move || store.counts()).await?;
    let token = escape(&survey.admin_token);
    let mut rows = String::new();
    for (q, n) in &counts.per_question {
        let _ = write!(rows, "<tr><td>{}</td><td>{n}</td></tr>", escape(q));
    }
    let mut links = String::new();
    for file in crate::export::EXPORT_FILES {
        let _ = write!(
            links,
            "<li><a href=\"/admin/export/{file}?token={token}\">{file}</a></li>"
        );
    }
    let html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta http-equiv=\"refresh\" content=\"10\"><title>Survey admin</title>\
         <link rel=\"stylesheet\" href=\"/assets/survey.css\"></head><body class=\"admin\">\
         <h1>Survey admin</h1><p>Refreshes every 10 s.</p><ul>\
         <li>Participants: {} started, {} finished</li>\
         <li>Answers: {} to real questions, {} to controls ({} questions per session)</li></ul>\
         <h2>Export</h2><ul>{links}</ul><h2>Answers per question</h2>\
         <table><tr><th>question</th><th>answers</th></tr>{rows}</table></body></html>\n",
        counts.participants,
        counts.finished,
        counts.answers,
        counts.control_answers,
        counts.questions
    );
    let mut response = html.into_response();
    let h = response.headers_mut();
    h.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("text/html; charset=utf-8"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    h.insert("referrer-policy", HeaderValue::from_static("no-referrer"));
    Ok(response)
}

async fn admin_export(
    State(survey): State<Arc<Survey>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
    Path(file): Path<String>,
) -> Result<Response, ApiError> {
    check_admin(&survey, &headers, &query)?;
    if !crate::export::EXPORT_FILES.contains(&file.as_str()) {
        return Err(ApiError::not_found(format!(
            "no such export file: {file} (one of {})",
            crate::export::EXPORT_FILES.join(", ")
        )));
    }
    let store = survey.store.clone();
    let export = blocking(move || store.export()).await?;
    let bytes = export
        .file(&file)
        .map(<[u8]>::to_vec)
        .ok_or_else(|| ApiError::internal(format!("export lacks {file}")))?;
    let content_type = if file.ends_with(".md") {
        "text/markdown; charset=utf-8"
    } else {
        "text/csv; charset=utf-8"
    };
    let mut response = bytes.into_response();
    let h = response.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{file}\"")) {
        h.insert(header::CONTENT_DISPOSITION, v);
    }
    Ok(response)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padding_reaches_every_size_from_the_minimum_on() {
        let gif = b"GIF89a...;".to_vec();
        for extra in [0, 5, 6, 7, 258, 259, 260, 261, 514, 515, 70_000] {
            let mut g = gif.clone();
            assert!(pad_gif(&mut g, gif.len() + extra), "{extra}");
            assert_eq!(g.len(), gif.len() + extra);
            assert_eq!(g.last(), Some(&0x3B));
            assert!(g.starts_with(&gif[..gif.len() - 1]));
        }
        for extra in [1, 2, 3, 4] {
            let mut g = gif.clone();
            assert!(!pad_gif(&mut g, gif.len() + extra));
            assert_eq!(g, gif);
        }
        let mut not_gif = b"abc".to_vec();
        assert!(!pad_gif(&mut not_gif, 100));
    }
}
