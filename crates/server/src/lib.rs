//! The project's web server: the survey that runs the questionnaire of a rendered run folder
//! for real and collects the answers safely in SQLite (axum on tokio; the page's HTML, CSS and
//! JavaScript sit in `assets/` and are embedded in the binary).
//!
//! - [`study`]: the questions of a run folder and each participant's plan (order seeded by the
//!   token, left/right swaps balanced across participants);
//! - [`store`]: the SQLite store (WAL, one transaction per answer) and its rules;
//! - [`clock`]: the time stamps the store and the export write;
//! - [`export`]: the stored answers as the files `experiments analyse` reads;
//! - [`survey`]: the survey's routes (participants, animations, admin);
//! - [`studio`]: the studio's routes (live extraction, compare, sculpt; three.js page) on a
//!   [`studio::Backend`] that the application provides;
//! - [`http`]: what any page of this crate shares (JSON errors, bounded bodies, tokens, embedded
//!   assets, running a router);
//! - [`error`]: the JSON error reply both share;
//! - [`serve`]: the connection loop both servers run on: read timeouts, a connection cap, size
//!   limits, and one JSON error shape for everything refused; [`write_stall`]: its write
//!   deadline for clients that stop reading.
//!
//! ```no_run
//! use std::path::Path;
//! use rmt_server::{store::Store, study::{Study, StudyOptions}, survey};
//!
//! let run = Path::new("runs/paper");
//! let study = Study::from_run(run, &StudyOptions::default())?;
//! let store = Store::open(&run.join("survey.sqlite"), &study)?;
//! let admin = rmt_server::http::random_token()?;
//! let router = survey::router(survey::Survey::new(store, run.join("render"), admin));
//! let running = rmt_server::http::spawn(router, "127.0.0.1:0".parse()?)?;
//! println!("survey at {}", running.url());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod clock;
pub mod error;
pub mod export;
pub mod http;
pub mod serve;
pub mod store;
pub mod studio;
pub mod study;
pub mod survey;
pub mod write_stall;
