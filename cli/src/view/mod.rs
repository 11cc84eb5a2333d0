//! The browser editor behind `meshpyr view`: a small HTTP server on
//! 127.0.0.1 that serves one embedded page (WebGL2, no external assets) and the `/api` it
//! uses — the spectrum as an equalizer, progressive-mesh levels, multiresolution edits and
//! exports, all computed by [`Pyramid`]. A scan over the display budget
//! ([`ViewServer::with_budget`]) is shown as a level of its progressive mesh: moves get a
//! preview at the shown vertices at once and the exact result from a background thread, which
//! exports use (`docs/view-api.md`). A scan whose pyramid takes long to make opens in stages
//! ([`ViewServer::opening`]): the page shows pictures of it, with the stage and progress, while
//! the pyramid is made on another thread.
//!
//! What it exposes and to whom (see also the README): the server listens on the loopback
//! interface only and answers only requests whose `Host` is `127.0.0.1:PORT` or
//! `localhost:PORT` (a page on another site reaching it through DNS rebinding gets 403);
//! every `/api` request must carry the random per-run token of the printed URL; bodies and
//! parameters are capped; and it never reads or writes a file: exports are downloads.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scan = meshpyr::read_mesh("scan.ply")?;
//! let server = meshpyr_cli::view::ViewServer::bind(meshpyr::Pyramid::build(&scan)?, 0)?;
//! println!("serving {}", server.url());
//! server.run()?; // until `server.stopper().stop()` is called from another thread
//! # Ok(()) }
//! ```

mod api;
mod background;
mod clustered;
mod editor;
mod guard;
mod http;
mod layout;
mod opening;
mod preview;
mod reply;
mod session;
mod state;
mod texture;

use http::{HttpRequest, Message};
use meshpyr::pyramid::{Pyramid, StagedPyramid};
use reply::Reply;
use session::Session;
use std::net::TcpListener;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};

pub use api::limits;
pub use clustered::first_picture;
pub use editor::{Answer, Editor, page_html};
pub use opening::{Opening, Picture};
pub use preview::{DEFAULT_BUDGET, EXACT_LEVELS};

/// Why the editor's server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The port could not be bound (in use, or not permitted).
    #[error("cannot listen on 127.0.0.1:{port}: {error}")]
    Bind {
        /// The port asked for (0: any free port).
        port: u16,
        /// What the system said.
        error: std::io::Error,
    },
    /// No randomness for the access token.
    #[error("cannot draw a random access token: {0}")]
    Token(std::io::Error),
    /// The scan being opened ([`ViewServer::opening`]) could not be: what its loader said.
    #[error("{0}")]
    Open(String),
}

/// The editor's HTTP server, bound and ready: [`ViewServer::run`] serves until stopped.
pub struct ViewServer {
    listener: TcpListener,
    port: u16,
    token: String,
    stage: Stage,
    /// Makes the pyramid of a scan still opening; taken when [`ViewServer::run`] starts it.
    loader: Option<Loader>,
    name: String,
    budget: usize,
    requests: Receiver<Message>,
    stopper: Stopper,
    /// When set, the rest of a staged pyramid is recorded only once this receives.
    hold_layout: Option<mpsc::Receiver<()>>,
}

/// What the loader of a scan opening in stages runs: the pyramid, or one line saying why not.
pub type Loader = Box<dyn FnOnce(&Opening) -> Result<Loaded, String> + Send>;

/// What a loader makes: the whole pyramid, or a staged one ([`meshpyr::pyramid::Staged`]),
/// whose editor is ready once the levels its previews synthesise are, while the rest of the
/// pyramid is recorded (`docs/view-api.md`, "A layout still being recorded").
pub enum Loaded {
    /// The whole pyramid.
    Whole(Pyramid),
    /// The pyramid up to the previews' exact level, and what records the rest.
    Staged(StagedPyramid),
}

impl From<Pyramid> for Loaded {
    fn from(pyramid: Pyramid) -> Loaded {
        Loaded::Whole(pyramid)
    }
}

/// A scan still opening (its pictures and progress), or the editor's session.
enum Stage {
    Opening(Opening),
    Ready(Box<Session>),
}

/// Stops a running [`ViewServer`] from another thread.
#[derive(Clone)]
pub struct Stopper {
    port: u16,
    stopped: Arc<AtomicBool>,
    worker: Sender<Message>,
}

impl Stopper {
    /// Makes [`ViewServer::run`] return after the request it is answering, if any, and stops
    /// accepting connections.
    pub fn stop(&self) {
        self.stopped.store(true, Ordering::SeqCst);
        let _ = self.worker.send(Message::Stop);
        // Wakes the acceptor, which then sees the flag.
        let _ = std::net::TcpStream::connect(("127.0.0.1", self.port));
    }
}

impl ViewServer {
    /// Listens on `127.0.0.1:port` (`0`: a free port) for the editor of `pyramid` (owned or
    /// shared), with a fresh random token.
    pub fn bind(pyramid: impl Into<Arc<Pyramid>>, port: u16) -> Result<ViewServer, ViewError> {
        ViewServer::bind_stage(Stage::Ready(Box::new(Session::new(pyramid))), None, port)
    }

    /// Listens on `127.0.0.1:port` for the editor of a scan whose pyramid `load` makes: until
    /// it returns, the page shows `first` (and what `load` shows through its [`Opening`]) with
    /// the stage and its progress. [`ViewServer::run`] starts `load` on its own thread and
    /// returns [`ViewError::Open`] when it fails.
    pub fn opening(
        first: Picture,
        load: impl FnOnce(&Opening) -> Result<Pyramid, String> + Send + 'static,
        port: u16,
    ) -> Result<ViewServer, ViewError> {
        let load = |opening: &Opening| load(opening).map(Loaded::Whole);
        ViewServer::opening_loaded(first, Box::new(load), port)
    }

    /// [`ViewServer::opening`] with a loader that may make a staged pyramid: the editor is
    /// then ready on its first stage, and the rest is recorded after the loader returns, on
    /// its thread; the calls that need the whole pyramid say it is pending until the session
    /// swaps it in.
    pub fn opening_loaded(
        first: Picture,
        load: Loader,
        port: u16,
    ) -> Result<ViewServer, ViewError> {
        let stage = Stage::Opening(Opening::new(first));
        ViewServer::bind_stage(stage, Some(load), port)
    }

    /// Holds the recording of a staged pyramid's rest until `until` receives (or its sender
    /// is dropped): the editor can then be seen, and tested, before the whole pyramid is in.
    pub fn holding_layout(mut self, until: mpsc::Receiver<()>) -> ViewServer {
        self.hold_layout = Some(until);
        self
    }

    fn bind_stage(
        stage: Stage,
        loader: Option<Loader>,
        port: u16,
    ) -> Result<ViewServer, ViewError> {
        let token = guard::random_token().map_err(ViewError::Token)?;
        let bind_error = |error| ViewError::Bind { port, error };
        let listener = TcpListener::bind(("127.0.0.1", port)).map_err(bind_error)?;
        let bound = listener.local_addr().map_err(bind_error)?.port();
        let (worker, requests) = http::worker_channel();
        Ok(ViewServer {
            listener,
            port: bound,
            token,
            stage,
            loader,
            name: "mesh".into(),
            budget: preview::DEFAULT_BUDGET,
            requests,
            hold_layout: None,
            stopper: Stopper {
                port: bound,
                stopped: Arc::new(AtomicBool::new(false)),
                worker,
            },
        })
    }

    /// Names the mesh (shown on the page and in export file names; default "mesh").
    pub fn with_name(mut self, name: &str) -> ViewServer {
        self.name = name.to_string();
        if let Stage::Ready(session) = &mut self.stage {
            session.name = self.name.clone();
        }
        self
    }

    /// Sets the display budget in triangles (default [`DEFAULT_BUDGET`]): a scan with more
    /// triangles is shown as the finest level of its progressive mesh within the budget, its
    /// previews computed at those vertices only and the exact result in the background.
    pub fn with_budget(mut self, triangles: usize) -> ViewServer {
        self.budget = triangles;
        if let Stage::Ready(session) = &mut self.stage {
            session.budget = triangles;
        }
        self
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// The per-run access token every `/api` request must carry.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// The page's address, token included: `http://127.0.0.1:PORT/?token=…`.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/?token={}", self.port, self.token)
    }

    /// A handle that stops [`ViewServer::run`] from another thread.
    pub fn stopper(&self) -> Stopper {
        self.stopper.clone()
    }

    /// Serves until [`Stopper::stop`]: connections are read on their own threads, requests
    /// answered here one at a time (synthesis uses every core already, so a second request
    /// would only wait for the first). A scan opening in stages is loaded on another thread
    /// meanwhile; its failure ends the serving with [`ViewError::Open`].
    pub fn run(mut self) -> Result<(), ViewError> {
        let worker = self.stopper.worker.clone();
        let stopped = Arc::clone(&self.stopper.stopped);
        let listener = self.listener.try_clone().map_err(|error| ViewError::Bind {
            port: self.port,
            error,
        })?;
        std::thread::spawn(move || http::accept(listener, worker, stopped));
        match (&mut self.stage, self.loader.take()) {
            (Stage::Opening(opening), Some(load)) => {
                let (opening, worker) = (opening.clone(), self.stopper.worker.clone());
                let (name, budget) = (self.name.clone(), self.budget);
                let hold = self.hold_layout.take();
                std::thread::spawn(move || {
                    let open = || {
                        load(&opening).map(|loaded| {
                            opening.stage("making the level of detail");
                            let (mut session, rest) = match loaded {
                                Loaded::Whole(pyramid) => (Session::new(pyramid), None),
                                Loaded::Staged(staged) => {
                                    let scan = Arc::new(staged.scan);
                                    let (job, wait) =
                                        layout::staged(Arc::clone(&scan), staged.rest, hold);
                                    (Session::staged(scan, staged.spectrum, wait), Some(job))
                                }
                            };
                            session.name = name;
                            session.budget = budget;
                            session.lod();
                            (Box::new(session), rest)
                        })
                    };
                    // A bug while opening must end the server, not leave the page waiting.
                    let opened = std::panic::catch_unwind(std::panic::AssertUnwindSafe(open))
                        .unwrap_or_else(|_| {
                            Err("internal error while opening (please report)".into())
                        });
                    let (opened, rest) = match opened {
                        Ok((session, rest)) => (Ok(session), rest),
                        Err(why) => (Err(why), None),
                    };
                    let _ = worker.send(Message::Opened(opened));
                    // The editor serves meanwhile; the session swaps the whole pyramid in.
                    if let Some(rest) = rest {
                        rest.run();
                    }
                });
            }
            // Over the budget, the level of detail is made now and its background work starts.
            (Stage::Ready(session), _) => {
                session.lod();
            }
            (Stage::Opening(_), None) => {}
        }
        while let Ok(message) = self.requests.recv() {
            match message {
                Message::Request(request, answer) => {
                    let _ = answer.send(self.answer(request));
                }
                Message::Opened(Ok(session)) => self.stage = Stage::Ready(session),
                Message::Opened(Err(why)) => return Err(ViewError::Open(why)),
                Message::Stop => break,
            }
        }
        Ok(())
    }

    fn answer(&mut self, request: HttpRequest) -> Reply {
        match guard::check(&request, self.port, &self.token) {
            Err(refused) => refused,
            Ok(guard::Route::Page(path)) => assets(&path),
            Ok(guard::Route::Api { path, query }) => match &mut self.stage {
                Stage::Opening(opening) => api::while_opening(opening, &request.method, &path),
                Stage::Ready(session) => {
                    editor::answer_api(session, &request.method, &path, &query, &request.body)
                }
            },
        }
    }
}

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");

/// The embedded page and its script.
fn assets(path: &str) -> Reply {
    match path {
        "/" | "/index.html" => Reply::bytes(200, "text/html; charset=utf-8", INDEX_HTML.into()),
        "/app.js" => Reply::bytes(200, "text/javascript; charset=utf-8", APP_JS.into()),
        _ => Reply::error(404, "no such page"),
    }
}
