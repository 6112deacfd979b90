//! What a render derives from (scene, settings) before its first wave, built once and shared
//! by every frame, viewer band and part cell that renders the same scene with the same
//! settings: the effects table, the [`Transport`] (light set and its sampling tables,
//! material table, textures, the camera fitted to the image, path rules) and the lane kernels that run.
//!
//! What one piece of such a render changes, the pixel rectangle and the range of sample
//! indices, is an [`Extent`] beside the plan, not part of it: a split render or the viewer's
//! bands build one plan and render many extents with it.

use super::Transport;
use super::bidir::KeptSplats;
use super::wavefront::Lanes;
use crate::effects::Effects;
use crate::scene::{Camera, Scene};
use crate::settings::{Cell, Settings};

/// Everything derived from one scene and one set of settings, ready for any number of
/// renders of parts of its image.
pub struct RenderPlan<'s> {
    /// The settings without a cell or a sample range (those are an [`Extent`]'s).
    settings: Settings,
    effects: Effects,
    transport: Transport<'s>,
    lanes: Lanes,
    /// path+light: the light passes' splats of recent iterations, for the next cell of the
    /// same samples (the viewer's bands).
    splats: KeptSplats,
}

/// The part of the image one render of a plan covers: a pixel rectangle (`None`: the whole
/// image) and a range of sample indices (`None`: 0 to the samples per pixel). A pixel gets
/// the same sums whatever extent covers it, so extents' sums merge into the whole render's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Extent {
    pub cell: Option<Cell>,
    pub samples: Option<(u32, u32)>,
}

impl Extent {
    /// The whole image, every sample.
    pub const WHOLE: Extent = Extent { cell: None, samples: None };

    /// The extent a set of settings asks for (its `-p` cell and sample range).
    pub fn of(settings: &Settings) -> Extent {
        Extent { cell: settings.image.cell, samples: settings.sampling.sample_range }
    }
}

impl<'s> RenderPlan<'s> {
    /// Evaluates the effects once and builds what shading reads from them; a cell or sample
    /// range in `settings` is not part of the plan (pass it as an [`Extent`]).
    pub fn new(scene: &'s Scene, settings: &Settings) -> Self {
        let mut settings = settings.clone();
        settings.image.cell = None;
        settings.sampling.sample_range = None;
        let effects = Effects::of(scene, &settings);
        // `--integrator auto` becomes the kind the scene's rule chose.
        settings.execution.integrator = effects.integrator_kind;
        let transport = Transport::new(scene, &settings, &effects);
        let lanes = Lanes::of(&transport, settings.execution.isa);
        RenderPlan { settings, effects, transport, lanes, splats: KeptSplats::default() }
    }

    /// Which stages and kernel parts the plan's renders run, and why.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// The settings the plan was built from, without cell or sample range.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    pub fn scene(&self) -> &'s Scene {
        self.transport.scene
    }

    /// The camera the plan's renders see through: the scene's camera fitted to the image by
    /// the settings' rule ([`ImageSettings::camera`](crate::settings::ImageSettings::camera)).
    pub fn camera(&self) -> &Camera {
        &self.transport.camera.camera
    }

    pub fn transport(&self) -> &Transport<'s> {
        &self.transport
    }

    pub fn lanes(&self) -> Lanes {
        self.lanes
    }

    /// What the plan's path+light renders of cells splatted lately, for the next cells.
    pub fn kept_splats(&self) -> &KeptSplats {
        &self.splats
    }

    /// The same plan tracing every ray from a last vertex, the emitter filter off: what the
    /// filter must not change.
    #[cfg(test)]
    pub fn tracing_every_ray(mut self) -> Self {
        self.transport.lights.emitters = None;
        self
    }

    /// The settings of one render of `extent`: the plan's, with its cell and sample range.
    pub fn settings_in(&self, extent: Extent) -> Settings {
        let mut s = self.settings.clone();
        s.image.cell = extent.cell;
        s.sampling.sample_range = extent.samples;
        s
    }
}
