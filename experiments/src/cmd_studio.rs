//! `experiments studio`: the interactive studio (live extraction with every `extract` parameter,
//! two configurations side by side, terrain sculpting) served from the binary; see
//! `rmt_server::studio` and [`crate::studio`].

use std::net::SocketAddr;
use std::sync::Arc;

use anyhow::Context;

use crate::config::default_threads;
use crate::studio::StudioBackend;

/// Arguments of `studio`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Address to listen on (port 0 picks a free one).
    #[arg(long, default_value = "127.0.0.1:8090")]
    pub addr: SocketAddr,
    /// Open the page in the default browser (xdg-open / open).
    #[arg(long)]
    pub open: bool,
    /// Worker threads of each extraction (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs `studio` until Ctrl-C.
pub fn run(args: Args) -> anyhow::Result<()> {
    let threads = args.threads.unwrap_or_else(default_threads);
    anyhow::ensure!(threads >= 1, "--threads must be at least 1");
    let studio = Arc::new(rmt_server::studio::Studio::new(StudioBackend::new(threads)));
    let router = rmt_server::studio::standalone_router(studio);
    let open = args.open;
    rmt_server::http::serve_until_ctrl_c(router, args.addr, |addr| {
        let url = format!("http://{addr}/studio/");
        println!("Studio: {url} ({threads} thread(s); Ctrl-C stops)");
        if open {
            open_browser(&url);
        }
    })
    .with_context(|| format!("serving on {}", args.addr))?;
    println!("Stopped.");
    Ok(())
}

fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    match std::process::Command::new(opener).arg(url).spawn() {
        Ok(_) => {}
        Err(e) => eprintln!("could not open a browser ({opener}: {e}); open {url} yourself"),
    }
}
