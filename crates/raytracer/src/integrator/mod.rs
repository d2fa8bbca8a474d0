//! Light-transport models, one module each, each with its own row loop, over shared code:
//! - [`classic`]: the course template's model (spec section 5), the default for course files,
//!   its pixels sampled by [`adaptive`] ([`adaptive::render_classic`]);
//! - [`photon`]: the course's photon mapper (spec section 10), over the [`photon_map`] and the
//!   same adaptive sampler ([`photon::render_rows`]);
//! - [`path`]: the physically based path tracer (spec section 11, [`path::render_sums`]);
//! - [`sppm`]: stochastic progressive photon mapping (spec section 11), over the same
//!   [`photon_map`] and the path tracer's camera walk ([`sppm::render_from`]).
//!
//! The course's two models share the lobes of [`course_lobes`]; the physically based ones share
//! the material lobes of [`bsdf`] and the light sampling of [`lights`]. Every model reports its
//! progress and work through [`report`]. Beside the models, [`aov`] computes the auxiliary
//! images (albedo, normal, depth) a denoiser reads.

pub mod adaptive;
pub mod aov;
pub mod bsdf;
pub mod bsdfs;
pub mod classic;
pub mod course_lobes;
pub mod direct;
pub mod emitters;
pub mod lights;
pub mod path;
pub mod photon;
pub mod photon_map;
pub mod physical;
pub mod report;
pub mod sppm;

pub use classic::Classic;

use crate::scene::{Algorithm, Diagnostic, Scene, Severity};

/// The light-transport models.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Model {
    /// The course template's model (spec section 5).
    Classic,
    /// The course's photon mapper (spec section 10).
    Photon,
    /// The physically based path tracer (spec section 11).
    Path,
    /// Stochastic progressive photon mapping (spec section 11).
    Sppm,
}

impl Model {
    /// Every model, in the order the help text lists them.
    pub const ALL: [Model; 4] = [Model::Classic, Model::Photon, Model::Path, Model::Sppm];

    /// The model's name on the command line (`--model NAME`).
    pub fn name(self) -> &'static str {
        match self {
            Model::Classic => "classic",
            Model::Photon => "photon",
            Model::Path => "path",
            Model::Sppm => "sppm",
        }
    }

    /// Whether the model reads the photon settings of the camera block.
    pub fn uses_photons(self) -> bool {
        matches!(self, Model::Photon | Model::Sppm)
    }

    /// Whether the model is physically based (reads `--max-depth`, writes unclamped radiance).
    pub fn is_physically_based(self) -> bool {
        matches!(self, Model::Path | Model::Sppm)
    }
}

/// The model a render uses: `requested` (the command line's `--model`) when given, otherwise the
/// one the scene's `algorithm=` names (`PPM` and `SPPM` both name [`Model::Sppm`]), otherwise
/// the classic model. Also returns the warnings the choice calls for: a scene set up for photon
/// mapping rendered by the classic model by default.
pub fn choose_model(scene: &Scene, requested: Option<Model>) -> (Model, Vec<Diagnostic>) {
    let mut notes = Vec::new();
    let from_file = scene.camera.algorithm.as_ref().map(|(algorithm, _)| match algorithm {
        Algorithm::RayTracing => Model::Classic,
        Algorithm::PhotonMapping => Model::Photon,
        Algorithm::ProgressivePhotonMapping | Algorithm::StochasticProgressivePhotonMapping => Model::Sppm,
    });
    let physical =
        !scene.emitters.is_empty() || scene.primitives.iter().any(|p| p.material.as_course().is_none());
    let default = if physical { Model::Path } else { Model::Classic };
    let model = requested.or(from_file).unwrap_or(default);
    if requested.is_none()
        && from_file.is_none()
        && let Some((key, location)) = scene.camera.photons.keys.first()
    {
        notes.push(Diagnostic {
            severity: Severity::Warning,
            message: format!(
                "this scene sets photon-mapping keys (`{key}=` ...) but renders with the classic model, \
                 which does not read them"
            ),
            location: Some(location.clone()),
            notes: vec![
                "render it with `--model photon` (or set `algorithm= PM` in the camera block)".into(),
            ],
        });
    }
    (model, notes)
}
