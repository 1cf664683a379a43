//! A write deadline for slow readers: a connection whose writes make no progress for the stall
//! timeout fails with `TimedOut`, so hyper drops it and its slot under the connection cap is
//! freed.
//!
//! ```text
//!   poll_write / poll_flush / poll_shutdown
//!     Ready  -> progress: the stall timer is disarmed
//!     Pending -> the timer is armed (once, at the first Pending since the last progress);
//!                if it has fired: Err(TimedOut)
//! ```
//!
//! Rules:
//! - only a stall counts: a client that keeps reading, however slowly, is never cut off, since
//!   every accepted byte disarms the timer;
//! - reads are not watched here (hyper's header timeout and the body timeout of [`crate::serve`]
//!   cover them);
//! - without it, a client that asks for a large reply (an animation) and never reads it holds
//!   its connection, and with enough of them the cap of [`crate::serve::Limits`], forever.

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::Sleep;

/// A connection whose writes fail after `timeout` without progress (see the module doc). Must
/// be polled inside a tokio runtime with its timer enabled.
pub struct WriteStall<T> {
    inner: T,
    timeout: Duration,
    stalled_since: Option<Pin<Box<Sleep>>>,
}

impl<T> WriteStall<T> {
    /// Wraps `inner`; a write that waits `timeout` without progress fails.
    pub fn new(inner: T, timeout: Duration) -> Self {
        Self {
            inner,
            timeout,
            stalled_since: None,
        }
    }

    /// Passes `poll` through, arming the timer on `Pending` and disarming it on `Ready`; a
    /// fired timer turns `Pending` into `TimedOut`.
    fn watch<R>(&mut self, cx: &mut Context<'_>, poll: Poll<io::Result<R>>) -> Poll<io::Result<R>> {
        match poll {
            Poll::Ready(result) => {
                self.stalled_since = None;
                Poll::Ready(result)
            }
            Poll::Pending => {
                let timeout = self.timeout;
                let timer = self
                    .stalled_since
                    .get_or_insert_with(|| Box::pin(tokio::time::sleep(timeout)));
                if timer.as_mut().poll(cx).is_ready() {
                    self.stalled_since = None;
                    return Poll::Ready(Err(io::Error::new(
                        io::ErrorKind::TimedOut,
                        format!("the client read nothing for {} s", timeout.as_secs_f64()),
                    )));
                }
                Poll::Pending
            }
        }
    }
}

impl<T: AsyncRead + Unpin> AsyncRead for WriteStall<T> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_read(cx, buf)
    }
}

impl<T: AsyncWrite + Unpin> AsyncWrite for WriteStall<T> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let poll = Pin::new(&mut self.inner).poll_write(cx, buf);
        self.watch(cx, poll)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let poll = Pin::new(&mut self.inner).poll_flush(cx);
        self.watch(cx, poll)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let poll = Pin::new(&mut self.inner).poll_shutdown(cx);
        self.watch(cx, poll)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::time::Instant;

    /// Writes `total` bytes through `w` in 64 KiB pieces; the first error, if any.
    async fn write_all<T: AsyncWrite + Unpin>(w: &mut T, total: usize) -> io::Result<()> {
        let piece = vec![7u8; 64 * 1024];
        let mut sent = 0;
        while sent < total {
            let n = std::future::poll_fn(|cx| Pin::new(&mut *w).poll_write(cx, &piece)).await?;
            sent += n;
        }
        Ok(())
    }

    /// A loopback connection: (the server's end, as tokio, and the client's, as std).
    fn pair(rt: &tokio::runtime::Runtime) -> (tokio::net::TcpStream, std::net::TcpStream) {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let client = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (server, _) = listener.accept().unwrap();
        server.set_nonblocking(true).unwrap();
        let _guard = rt.enter();
        (tokio::net::TcpStream::from_std(server).unwrap(), client)
    }

    fn runtime() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
    }

    /// A client that never reads: once the socket buffers are full, the write fails after the
    /// stall timeout (not before, and not much later).
    #[test]
    fn a_stalled_write_fails_after_the_timeout() {
        let rt = runtime();
        let (server, _client) = pair(&rt);
        let mut w = WriteStall::new(server, Duration::from_millis(400));
        let start = Instant::now();
        let err = rt.block_on(write_all(&mut w, 1 << 30)).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::TimedOut);
        assert!(err.to_string().contains("read nothing for 0.4 s"), "{err}");
        let waited = start.elapsed();
        assert!(
            waited >= Duration::from_millis(400) && waited < Duration::from_secs(10),
            "{waited:?}"
        );
    }

    /// A client that reads slowly but steadily (1 MiB every 150 ms, far slower than the writer)
    /// is never cut off by a 1 s stall timeout, although the whole transfer takes longer.
    #[test]
    fn a_slow_reader_is_not_cut_off() {
        let rt = runtime();
        let (server, mut client) = pair(&rt);
        let total = 24 << 20;
        let reader = std::thread::spawn(move || {
            let mut buf = vec![0u8; 1 << 20];
            let mut got = 0;
            while got < total {
                std::thread::sleep(Duration::from_millis(150));
                let mut chunk = 0;
                while chunk < buf.len() && got < total {
                    let n = client.read(&mut buf[chunk..]).unwrap();
                    assert!(n > 0, "closed early");
                    chunk += n;
                    got += n;
                }
            }
            got
        });
        let mut w = WriteStall::new(server, Duration::from_secs(1));
        let start = Instant::now();
        rt.block_on(write_all(&mut w, total))
            .expect("a steady reader is not cut off");
        assert_eq!(reader.join().unwrap(), total);
        assert!(
            start.elapsed() > Duration::from_secs(1),
            "{:?}",
            start.elapsed()
        );
    }
}
