//! Opening a scan in stages. Building a large scan's pyramid takes minutes, and a viewer that
//! shows nothing until then is no viewer: the server answers from the start with a first
//! picture (the input clustered to the display budget, or a `.pyr` file's level within it, read
//! from the file's prefix), the loader replaces it by the hierarchy's level as soon as the
//! progressive mesh is built, and the page draws each picture with the stage and its progress
//! until the pyramid is ready and the editor takes over.

use super::session::push_u32_triples;
use glam::DVec3;
use serde_json::json;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

/// A picture of the scan shown while it opens: triangles on their own vertices, and what it is.
#[derive(Clone, Debug)]
pub struct Picture {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    what: String,
}

impl Picture {
    /// The triangles `triangles` on `positions` (every index must be below `positions.len()`),
    /// described by `what` (shown in the page: "the input clustered to …", "level … of …").
    pub fn new(what: impl Into<String>, positions: &[DVec3], triangles: Vec<[u32; 3]>) -> Picture {
        debug_assert!(
            triangles
                .iter()
                .flatten()
                .all(|&i| (i as usize) < positions.len())
        );
        Picture {
            positions: positions.iter().map(|p| p.as_vec3().to_array()).collect(),
            triangles,
            what: what.into(),
        }
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// What the picture is.
    pub fn what(&self) -> &str {
        &self.what
    }

    /// `/api/opening`: u32 vertex and triangle counts, f32 position triples, u32 triangle
    /// triples (the layout of `/api/level`).
    pub(super) fn bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(8 + 12 * (self.positions.len() + self.triangles.len()));
        out.extend_from_slice(&(self.positions.len() as u32).to_le_bytes());
        out.extend_from_slice(&(self.triangles.len() as u32).to_le_bytes());
        for x in self.positions.iter().flatten() {
            out.extend_from_slice(&x.to_le_bytes());
        }
        push_u32_triples(&mut out, &self.triangles);
        out
    }

    /// Its bounding box, for the page's camera.
    pub(super) fn bbox(&self) -> ([f32; 3], [f32; 3]) {
        self.positions.iter().fold(
            ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(lo, hi), p| {
                (
                    std::array::from_fn(|k| lo[k].min(p[k])),
                    std::array::from_fn(|k| hi[k].max(p[k])),
                )
            },
        )
    }
}

/// The loader's side of an opening scan: it names the stage, reports progress and replaces the
/// picture; the server reads them for `/api/status` and `/api/opening`. Cheap to clone.
#[derive(Clone)]
pub struct Opening {
    shared: Arc<Mutex<OpeningState>>,
}

struct OpeningState {
    stage: String,
    done: f64,
    picture: Arc<Picture>,
    /// Pictures shown so far: the page fetches the picture again when this changes.
    pictures: u32,
    since: Instant,
}

impl Opening {
    pub(crate) fn new(first: Picture) -> Opening {
        Opening {
            shared: Arc::new(Mutex::new(OpeningState {
                stage: "starting".into(),
                done: 0.0,
                picture: Arc::new(first),
                pictures: 1,
                since: Instant::now(),
            })),
        }
    }

    fn state(&self) -> MutexGuard<'_, OpeningState> {
        // A loader that panicked while holding the lock left only numbers behind.
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Names the stage the loader is in (shown in the page with the progress).
    pub fn stage(&self, stage: &str) {
        self.state().stage = stage.to_string();
    }

    /// The fraction of the whole opening done.
    pub fn progress(&self, fraction: f64) {
        self.state().done = fraction.clamp(0.0, 1.0);
    }

    /// Shows `picture` instead of the one shown.
    pub fn show(&self, picture: Picture) {
        let mut s = self.state();
        s.picture = Arc::new(picture);
        s.pictures += 1;
    }

    /// `/api/status` while opening.
    pub(crate) fn status(&self) -> serde_json::Value {
        let s = self.state();
        let (min, max) = s.picture.bbox();
        let diagonal = (0..3)
            .map(|k| f64::from(max[k] - min[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        json!({"opening": {
            "stage": s.stage, "done": s.done, "seconds": s.since.elapsed().as_secs_f64(),
            "picture": s.pictures, "what": s.picture.what, "triangles": s.picture.n_triangles(),
            "bbox": {"min": min, "max": max}, "diagonal": diagonal,
        }})
    }

    /// `/api/opening`: the picture shown, and its number.
    pub(crate) fn picture_bytes(&self) -> (Vec<u8>, u32) {
        let (picture, number) = {
            let s = self.state();
            (Arc::clone(&s.picture), s.pictures)
        };
        (picture.bytes(), number)
    }

    /// The current stage, for refusals while opening.
    pub(crate) fn stage_name(&self) -> String {
        self.state().stage.clone()
    }
}

impl meshpyr::progress::Progress for Opening {
    fn update(&self, fraction: f64) {
        self.progress(fraction);
    }
}
