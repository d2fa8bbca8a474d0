//! What a model reports: its progress by stage while it renders, and the counts of its work
//! (with the photon map's and SPPM's own).

use std::time::Duration;

use glam::DVec3;

/// The stage a progress report is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Tracing photons from the lights (photon model; units are photons).
    TracingPhotons,
    /// Building the photon map's search tree (one unit).
    BuildingPhotonMap,
    /// Tracing every pixel.
    Tracing,
    /// Re-rendering the pixels on edges (adaptive mode).
    Refining,
    /// Path tracing (units are samples: pixels times samples a pixel).
    Sampling,
    /// SPPM passes (units are passes).
    Passes,
    /// Chunks of rows of a render that keeps a checkpoint (units are chunks).
    Chunks,
}

/// A progress report: `done` of `total` units (rows while tracing, pixels while refining, samples
/// while path tracing, passes of SPPM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The stage.
    pub stage: Stage,
    /// Units finished.
    pub done: u64,
    /// Units in the stage.
    pub total: u64,
}

/// Counts of the work a render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Rays traced: camera, reflected, refracted, glossy and shadow rays.
    pub rays: u64,
    /// Camera samples taken.
    pub camera_samples: u64,
    /// Pixels re-rendered by adaptive anti-aliasing.
    pub refined_pixels: u64,
    /// Worker threads used.
    pub threads: usize,
    /// Photon-map irradiance estimates (photon model).
    pub lookups: u64,
    /// The photon map's making (photon model).
    pub photons: Option<PhotonStats>,
    /// The passes and photons of an SPPM render.
    pub sppm: Option<SppmStats>,
}

impl RenderStats {
    /// Adds the work of another run or portion (threads are kept).
    pub fn add(&mut self, other: &RenderStats) {
        self.rays += other.rays;
        self.camera_samples += other.camera_samples;
        self.refined_pixels += other.refined_pixels;
        self.lookups += other.lookups;
        self.photons = match (self.photons, other.photons) {
            (Some(a), Some(b)) => Some(a.add(&b)),
            (a, b) => a.or(b),
        };
        self.sppm = match (self.sppm, other.sppm) {
            (Some(a), Some(b)) => Some(a.add(&b)),
            (a, b) => a.or(b),
        };
    }
}

/// What building a photon map took.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhotonStats {
    /// Photons the scene asks for (`emit_photons=`, or `--photons`): the estimate's divisor.
    pub requested: u64,
    /// Photons traced (fewer than requested when the map filled up first).
    pub emitted: u64,
    /// Photons stored in the map.
    pub stored: u64,
    /// Rays traced for the photons.
    pub rays: u64,
    /// Time spent tracing photons.
    pub trace_time: Duration,
    /// Time spent building the k-d tree.
    pub build_time: Duration,
    /// Bytes the map holds.
    pub map_bytes: u64,
}

impl PhotonStats {
    /// The statistics of two photon maps together.
    pub fn add(&self, other: &PhotonStats) -> PhotonStats {
        PhotonStats {
            requested: self.requested + other.requested,
            emitted: self.emitted + other.emitted,
            stored: self.stored + other.stored,
            rays: self.rays + other.rays,
            trace_time: self.trace_time + other.trace_time,
            build_time: self.build_time + other.build_time,
            map_bytes: self.map_bytes.max(other.map_bytes),
        }
    }
}

/// What an SPPM render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SppmStats {
    /// Passes made.
    pub passes: u64,
    /// Photons emitted in all.
    pub photons: u64,
    /// Photons stored in all.
    pub stored: u64,
    /// Rays traced (camera paths, shadow rays, photons).
    pub rays: u64,
    /// Seconds spent tracing photons and building their maps.
    pub photon_seconds: f64,
    /// The mean final radius over the pixels with a visible point, in world units.
    pub mean_radius: f64,
}

impl SppmStats {
    /// The statistics of two runs together (the mean radius is their mean).
    pub fn add(&self, other: &SppmStats) -> SppmStats {
        SppmStats {
            passes: self.passes + other.passes,
            photons: self.photons + other.photons,
            stored: self.stored + other.stored,
            rays: self.rays + other.rays,
            photon_seconds: self.photon_seconds + other.photon_seconds,
            mean_radius: (self.mean_radius + other.mean_radius) / 2.0,
        }
    }
}

/// What a camera path met.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathResult {
    /// Radiance gathered along the path.
    pub radiance: DVec3,
    /// Rays traced (path segments and shadow rays).
    pub rays: u64,
}
