//! A part's statistics, kept in its file, and the statistics of a merged render.

use serde::{Deserialize, Serialize};
use wavepath::{RenderStats, StageTimes};

/// What one part did and how long it took.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct PartStats {
    pub host: String,
    pub camera_rays: u64,
    pub extension_rays: u64,
    pub shadow_rays: u64,
    /// Rays of light subpaths (path+light); absent from parts written before they were counted.
    #[serde(default)]
    pub light_rays: u64,
    pub prim_tests: u64,
    pub nodes: u64,
    /// Thread-seconds per stage; a stage that did not run stays absent.
    pub stages: StageTimes,
    /// Seconds in the integrator.
    pub render_s: f64,
    /// Seconds from the start of the process to the part file being complete (load, BVH
    /// build, render, encode).
    pub wall_s: f64,
    pub build_s: f64,
    pub threads: usize,
}

impl PartStats {
    pub fn add_render(&mut self, st: &RenderStats) {
        self.camera_rays += st.camera_rays;
        self.extension_rays += st.extension_rays;
        self.shadow_rays += st.shadow_rays;
        self.light_rays += st.light_rays;
        self.prim_tests += st.counters.prim_tests;
        self.nodes += st.counters.nodes;
        self.stages.add(&st.stages);
        self.render_s += st.render_s;
    }

    pub fn rays(&self) -> u64 {
        self.camera_rays + self.extension_rays + self.shadow_rays + self.light_rays
    }
}
