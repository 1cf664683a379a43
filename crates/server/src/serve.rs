//! Serving a router on tokio with production limits: a read timeout for request heads (which also
//! closes idle kept-alive connections), a read timeout for bodies, a write deadline for clients
//! that stop reading ([`crate::write_stall`]), a cap on concurrent connections, size limits for the URI, the head and the body, and one JSON error shape for
//! everything the server refuses, including what hyper answers on its own (`400`, `414`, `431`
//! for heads it cannot parse).

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{ready, Context, Poll};
use std::time::Duration;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::server::graceful::GracefulShutdown;
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpListener;
use tokio::sync::Semaphore;

use crate::error::ApiError;
use crate::write_stall::WriteStall;

/// The limits a server applies to every connection; [`Limits::default`] is what the survey and
/// the studio use (README, "Limits").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Time a client has to send a request's head (request line and headers) from the moment
    /// the server waits for it: on a new connection, and between requests on a kept-alive one,
    /// so an idle connection is closed after this long.
    pub header_timeout: Duration,
    /// Time a client has to send a request's whole body once its head has arrived (`408`).
    pub body_timeout: Duration,
    /// Time a reply may wait for the client to read any of it; then the connection is closed
    /// (a client reading slowly but steadily is never cut off: see [`crate::write_stall`]).
    pub write_timeout: Duration,
    /// Connections served at once; more wait in the listen backlog until one closes.
    pub max_connections: usize,
    /// Longest request target (path and query), bytes (`414`).
    pub max_uri_bytes: usize,
    /// Largest request head, bytes (`431`).
    pub max_head_bytes: usize,
    /// Largest request body any route reads, bytes (`413`); routes have lower limits of their
    /// own.
    pub max_body_bytes: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            header_timeout: Duration::from_secs(30),
            body_timeout: Duration::from_secs(30),
            write_timeout: Duration::from_secs(30),
            max_connections: 512,
            max_uri_bytes: 8 * 1024,
            max_head_bytes: 32 * 1024,
            max_body_bytes: 64 * 1024,
        }
    }
}

/// Serves `router` on `listener` under `limits` until `shutdown` completes, then stops accepting
/// and lets the open connections finish their requests.
pub async fn serve(
    listener: TcpListener,
    router: Router,
    limits: Limits,
    shutdown: impl Future<Output = ()>,
) -> io::Result<()> {
    let app = router.layer(axum::middleware::from_fn_with_state(limits, guard));
    let permits = Arc::new(Semaphore::new(limits.max_connections.max(1)));
    let graceful = GracefulShutdown::new();
    let mut shutdown = std::pin::pin!(shutdown);
    loop {
        let permit = tokio::select! {
            permit = permits.clone().acquire_owned() => permit.map_err(io::Error::other)?,
            () = &mut shutdown => break,
        };
        let stream = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => stream,
                Err(e) => {
                    // Out of file descriptors or a connection reset before accept: wait a
                    // little (the open connections time out and free descriptors) and go on.
                    eprintln!("accept failed: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
            () = &mut shutdown => break,
        };
        let _ = stream.set_nodelay(true);
        let mut builder = http1::Builder::new();
        builder
            .timer(TokioTimer::new())
            .header_read_timeout(limits.header_timeout)
            .max_buf_size(limits.max_head_bytes.max(8192));
        let conn = builder.serve_connection(
            TokioIo::new(JsonAutoErrors::new(WriteStall::new(
                stream,
                limits.write_timeout,
            ))),
            TowerToHyperService::new(app.clone()),
        );
        let conn = graceful.watch(conn);
        tokio::spawn(async move {
            // Errors here are the client's (timeouts, resets, malformed heads): hyper has
            // already answered what could be answered.
            let _ = conn.await;
            drop(permit);
        });
    }
    drop(listener);
    graceful.shutdown().await;
    Ok(())
}

fn close(mut response: Response) -> Response {
    response
        .headers_mut()
        .insert(header::CONNECTION, HeaderValue::from_static("close"));
    response
}

/// The limits on the request (URI, body size and body time) before the router, and the one
/// error shape after it: any error reply that is not JSON yet (axum's rejections, `405`, a
/// router without a fallback's `404`) becomes `{"error": "..."}` with its text as the message.
async fn guard(State(limits): State<Limits>, request: Request, next: Next) -> Response {
    let path = request.uri().path().to_string();
    let target = request
        .uri()
        .path_and_query()
        .map_or(0, |p| p.as_str().len());
    if target > limits.max_uri_bytes {
        return close(
            ApiError::new(
                StatusCode::URI_TOO_LONG,
                format!(
                    "request URI too long: {target} bytes (at most {})",
                    limits.max_uri_bytes
                ),
            )
            .into_response(),
        );
    }
    let declared = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    if declared.is_some_and(|n| n > limits.max_body_bytes as u64) {
        return close(too_large(limits.max_body_bytes));
    }
    let (parts, body) = request.into_parts();
    let read = axum::body::to_bytes(body, limits.max_body_bytes);
    let bytes = match tokio::time::timeout(limits.body_timeout, read).await {
        Ok(Ok(bytes)) => bytes,
        Ok(Err(e)) => {
            let too_big = std::error::Error::source(&e)
                .is_some_and(|s| s.is::<http_body_util::LengthLimitError>());
            return close(if too_big {
                too_large(limits.max_body_bytes)
            } else {
                ApiError::bad_request(format!("could not read the request body: {e}"))
                    .into_response()
            });
        }
        Err(_) => {
            return close(
                ApiError::new(
                    StatusCode::REQUEST_TIMEOUT,
                    format!(
                        "the request body did not arrive within {} s",
                        limits.body_timeout.as_secs_f64()
                    ),
                )
                .into_response(),
            )
        }
    };
    let response = next
        .run(Request::from_parts(parts, Body::from(bytes)))
        .await;
    json_error(response, &path).await
}

fn too_large(limit: usize) -> Response {
    ApiError::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        format!("request body too large (at most {limit} bytes)"),
    )
    .into_response()
}

/// An error reply that is not JSON, rewritten as [`ApiError`]'s `{"error": "..."}` (headers such
/// as `Allow` kept).
async fn json_error(response: Response, path: &str) -> Response {
    let status = response.status();
    let is_json = response
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    if !(status.is_client_error() || status.is_server_error()) || is_json {
        return response;
    }
    let (mut parts, body) = response.into_parts();
    let text = axum::body::to_bytes(body, 4096)
        .await
        .map(|b| String::from_utf8_lossy(&b).trim().to_string())
        .unwrap_or_default();
    let message = if !text.is_empty() {
        text
    } else {
        match status {
            StatusCode::NOT_FOUND => format!("no such page: {path}"),
            StatusCode::METHOD_NOT_ALLOWED => {
                let allow = parts
                    .headers
                    .get(header::ALLOW)
                    .and_then(|v| v.to_str().ok())
                    .unwrap_or("");
                format!("method not allowed on {path} (allowed: {allow})")
            }
            s => s
                .canonical_reason()
                .unwrap_or("request refused")
                .to_string(),
        }
    };
    let mut reply = ApiError::new(status, message).into_response();
    parts.headers.remove(header::CONTENT_LENGTH);
    parts.headers.remove(header::CONTENT_TYPE);
    for (name, value) in &parts.headers {
        reply.headers_mut().entry(name).or_insert(value.clone());
    }
    reply
}

/// hyper answers heads it cannot parse itself, with an empty body: `400` (malformed), `414` (a
/// target over 64 KiB), `431` (a head over the buffer limit). This wrapper of the connection
/// recognises such a reply (a lone 4xx head with `content-length: 0` and no content type, which
/// no route sends: every route error has a JSON body) and sends it with a JSON body in the
/// routes' shape instead.
pub struct JsonAutoErrors<T> {
    inner: T,
    pending: Vec<u8>,
    at: usize,
}

impl<T> JsonAutoErrors<T> {
    /// Wraps a connection.
    pub fn new(inner: T) -> Self {
        Self {
            inner,
            pending: Vec::new(),
            at: 0,
        }
    }
}

impl<T: AsyncWrite + Unpin> JsonAutoErrors<T> {
    fn poll_pending(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        while self.at < self.pending.len() {
            let n = ready!(Pin::new(&mut self.inner).poll_write(cx, &self.pending[self.at..]))?;
            if n == 0 {
                return Poll::Ready(Err(io::ErrorKind::WriteZero.into()));
            }
            self.at += n;
        }
        self.pending.clear();
        self.at = 0;
        Poll::Ready(Ok(()))
    }
}

/// hyper's reply to an unparsable head, rewritten with a JSON body; `None` for anything else.
pub fn rewrite_automatic_reply(buf: &[u8]) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(buf).ok()?;
    let end = text.find("\r\n\r\n")?;
    if end + 4 != text.len() {
        return None;
    }
    let rest = text
        .strip_prefix("HTTP/1.1 ")
        .or_else(|| text.strip_prefix("HTTP/1.0 "))?;
    let code: u16 = rest.get(..3)?.parse().ok()?;
    if !(400..500).contains(&code) {
        return None;
    }
    let lower = text.to_ascii_lowercase();
    if !lower.contains("\r\ncontent-length: 0\r\n") || lower.contains("\r\ncontent-type:") {
        return None;
    }
    let message = match code {
        400 => "malformed HTTP request".to_string(),
        414 => "request URI too long".to_string(),
        431 => "request headers too large".to_string(),
        c => StatusCode::from_u16(c)
            .ok()
            .and_then(|s| s.canonical_reason())
            .unwrap_or("request refused")
            .to_string(),
    };
    let body = serde_json::json!({ "error": message }).to_string();
    let mut out = String::with_capacity(end + 160 + body.len());
    for line in text[..end].split("\r\n") {
        if line.to_ascii_lowercase().starts_with("content-length:") {
            out.push_str(&format!("content-length: {}", body.len()));
        } else {
            out.push_str(line);
        }
        out.push_str("\r\n");
    }
    if !lower.contains("\r\nconnection:") {
        out.push_str("connection: close\r\n");
    }
    out.push_str("content-type: application/json\r\ncache-control: no-store\r\n\r\n");
    out.push_str(&body);
    Some(out.into_bytes())
}

impl<T: AsyncRead + Unpin> AsyncRead for JsonAutoErrors<T> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_read(cx, buf)
    }
}

impl<T: AsyncWrite + Unpin> AsyncWrite for JsonAutoErrors<T> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        ready!(self.poll_pending(cx))?;
        if let Some(rewritten) = rewrite_automatic_reply(buf) {
            self.pending = rewritten;
            self.at = 0;
            // Sent by the next write, flush or shutdown if the socket is full now.
            if let Poll::Ready(Err(e)) = self.poll_pending(cx) {
                return Poll::Ready(Err(e));
            }
            return Poll::Ready(Ok(buf.len()));
        }
        Pin::new(&mut self.inner).poll_write(cx, buf)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        ready!(self.poll_pending(cx))?;
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        ready!(self.poll_pending(cx))?;
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }
}
