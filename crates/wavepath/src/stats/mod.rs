//! Render statistics: what was traced, how fast, and where the time went.

use crate::accel::TraceCounters;
use serde::{Deserialize, Serialize};

/// Seconds spent in each wavefront stage, summed over worker threads (thread-seconds); `None`
/// for a stage that did not run (it is then absent from the stats JSON).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct StageTimes {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generate: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub traverse: Option<f64>,
    /// The output variables' first hits (only when a render keeps them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aov: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shade: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shadow: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compact: Option<f64>,
    /// Bidirectional transport: tracing light subpaths (their camera connections included).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_paths: Option<f64>,
    /// Bidirectional transport: the hash grid over light vertices (merging).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_grid: Option<f64>,
    /// Bidirectional transport: tracing camera subpaths and joining them to light.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera_paths: Option<f64>,
}

impl StageTimes {
    pub fn total(&self) -> f64 {
        self.list().iter().map(|(_, t)| t).sum()
    }

    /// The stages that ran, in pipeline order, with their seconds.
    pub fn list(&self) -> Vec<(&'static str, f64)> {
        [
            ("generate", self.generate),
            ("traverse", self.traverse),
            ("aov", self.aov),
            ("shade", self.shade),
            ("shadow", self.shadow),
            ("compact", self.compact),
            ("light_paths", self.light_paths),
            ("merge_grid", self.merge_grid),
            ("camera_paths", self.camera_paths),
        ]
        .into_iter()
        .filter_map(|(n, t)| t.map(|t| (n, t)))
        .collect()
    }

    /// Adds `o`'s times; a stage ran if it ran in either.
    pub fn add(&mut self, o: &StageTimes) {
        let sum = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0.0) + b.unwrap_or(0.0)),
        };
        self.generate = sum(self.generate, o.generate);
        self.traverse = sum(self.traverse, o.traverse);
        self.shade = sum(self.shade, o.shade);
        self.shadow = sum(self.shadow, o.shadow);
        self.compact = sum(self.compact, o.compact);
        self.aov = sum(self.aov, o.aov);
        self.light_paths = sum(self.light_paths, o.light_paths);
        self.merge_grid = sum(self.merge_grid, o.merge_grid);
        self.camera_paths = sum(self.camera_paths, o.camera_paths);
    }
}

/// Everything a render reports besides its image.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub camera_rays: u64,
    pub extension_rays: u64,
    pub shadow_rays: u64,
    /// Rays of light subpaths: from the lights and between light vertices (their camera
    /// connections are shadow rays).
    pub light_rays: u64,
    pub counters: TraceCounters,
    pub stages: StageTimes,
    pub render_s: f64,
    /// Samples dropped because they were NaN or Inf.
    pub invalid_samples: u64,
    /// Camera samples taken per rendered pixel.
    pub samples_per_pixel: Vec<u32>,
}

impl RenderStats {
    pub fn total_rays(&self) -> u64 {
        self.camera_rays + self.extension_rays + self.shadow_rays + self.light_rays
    }

    /// Nanoseconds of thread time per vertex of each side, (camera, light), when a render
    /// traced light subpaths beside the wavefront's camera paths: the camera side's stages over
    /// its camera and extension rays (one vertex each), the light stage over its light rays.
    /// The two sides' costs compare here, so a side run one path at a time would show.
    pub fn ns_per_vertex(&self) -> Option<(f64, f64)> {
        let s = &self.stages;
        let light = s.light_paths?;
        let camera = s.generate? + s.traverse? + s.shade? + s.shadow.unwrap_or(0.0) + s.compact.unwrap_or(0.0);
        let per = |t: f64, n: u64| t * 1e9 / n.max(1) as f64;
        (self.light_rays > 0).then(|| {
            (per(camera + s.aov.unwrap_or(0.0), self.camera_rays + self.extension_rays), per(light, self.light_rays))
        })
    }

    pub fn mrays_per_s(&self) -> f64 {
        if self.render_s > 0.0 { self.total_rays() as f64 / self.render_s / 1e6 } else { 0.0 }
    }

    pub fn tests_per_ray(&self) -> f64 {
        self.counters.prim_tests as f64 / self.counters.rays.max(1) as f64
    }

    pub fn nodes_per_ray(&self) -> f64 {
        self.counters.nodes as f64 / self.counters.rays.max(1) as f64
    }

    /// (mean, min, max) camera samples per pixel.
    pub fn spp_summary(&self) -> (f64, u32, u32) {
        let n = self.samples_per_pixel.len().max(1) as f64;
        let sum: u64 = self.samples_per_pixel.iter().map(|&s| s as u64).sum();
        let min = self.samples_per_pixel.iter().copied().min().unwrap_or(0);
        let max = self.samples_per_pixel.iter().copied().max().unwrap_or(0);
        (sum as f64 / n, min, max)
    }

    /// The seed-style summary printed at the end of a render.
    pub fn log_lines(&self) -> Vec<String> {
        let s = &self.stages;
        let mut lines = vec![
            format!(
                "Rays traced: {} (camera {}, extension {}, shadow {}{})",
                self.total_rays(),
                self.camera_rays,
                self.extension_rays,
                self.shadow_rays,
                if self.light_rays > 0 { format!(", light {}", self.light_rays) } else { String::new() }
            ),
            format!("Render time: {:.4} s", self.render_s),
            format!("Average speed: {:.3} million rays per second", self.mrays_per_s()),
            format!(
                "Averaged {:.3} intersection tests per ray, {:.3} nodes visited per ray",
                self.tests_per_ray(),
                self.nodes_per_ray()
            ),
            format!(
                "Stages (thread-seconds, summed over worker threads): {}",
                s.list().iter().map(|(n, t)| format!("{n} {t:.4}")).collect::<Vec<_>>().join(", ")
            ),
            format!("Invalid (NaN/Inf) samples dropped: {}", self.invalid_samples),
        ];
        if let Some((camera, light)) = self.ns_per_vertex() {
            lines.insert(
                lines.len() - 1,
                format!(
                    "Thread time per vertex: camera side {camera:.0} ns, light side {light:.0} ns ({:.2}x)",
                    light / camera
                ),
            );
        }
        lines
    }
}

mod json;
pub use json::{roulette_json, to_json};
