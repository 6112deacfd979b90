//! The one scene model every loader produces and every stage reads.
//!
//! Geometry is flattened into world space at load time so that the accelerator and the
//! integrator never see node hierarchies or file-format quirks.

pub mod alpha;
mod camera;
mod camera_file;
pub mod envmap;
pub mod layers;

mod material;
mod material_ids;
mod mesh;
mod normals;
pub mod relief;
pub mod subdivide;
pub mod surface;
pub mod texture;

pub use alpha::{Alpha, AlphaMode};
pub use camera::{CS184_FOCAL_DISTANCE, Camera, FovFit, FovRule};
pub use camera_file::{format_camera_settings, parse_camera_settings, read_camera_file};
pub use envmap::EnvMap;
pub use material::{Bsdf, Layers, Material, Relief, ReliefMap, SpecularGlossinessMap, Texture, phong_alpha};
pub use material_ids::MaterialIds;
pub use mesh::{Mesh, Sphere, first_bad};
pub use normals::{area_weighted_vertex_normals, cs184_vertex_normals};
#[cfg(test)]
pub use surface::SurfacePoint;
pub use texture::Textures;

use crate::cs184::Dialect;
use glam::Vec3;

/// A light source as the file describes it, in world space.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light; `intensity` is radiant intensity per channel.
    /// `attenuation` = (constant, linear, quadratic) as COLLADA gives it; the CS184 reference ignores it.
    Point { position: Vec3, intensity: Vec3, attenuation: [f32; 3] },
    /// Light arriving along `direction` (the direction the light travels), radiance `radiance`.
    Directional { direction: Vec3, radiance: Vec3 },
    /// Spot light: a point light restricted to a cone around `direction`; `cone_angle` is
    /// COLLADA's `falloff_angle`, the full cone angle in degrees.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cone_angle: f32, falloff_exponent: f32 },
    /// Constant radiance from every direction of the upper (world +Y) hemisphere: the CS184 ambient light.
    Hemisphere { radiance: Vec3 },
    /// One-sided emitting parallelogram (CS184 area light), centred at `position`,
    /// spanning ±dim_x/2 and ±dim_y/2, emitting toward `direction`.
    Area { position: Vec3, direction: Vec3, dim_x: Vec3, dim_y: Vec3, radiance: Vec3 },
}

impl Light {
    /// Short lowercase name used by `info` and the render log.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Point { .. } => "point",
            Light::Directional { .. } => "directional",
            Light::Spot { .. } => "spot",
            Light::Hemisphere { .. } => "hemisphere",
            Light::Area { .. } => "area",
        }
    }

    /// True for lights that need exactly one shadow sample (no extent).
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point { .. } | Light::Directional { .. } | Light::Spot { .. })
    }
}

/// Light arriving from infinity in directions no geometry covers.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Environment {
    /// Black: nothing arrives from outside the scene.
    #[default]
    None,
    /// The same radiance from every direction.
    Constant(Vec3),
    /// An equirectangular (lat-long) map, linear RGB, row 0 at the top (+Y); loaded once
    /// with its sampling distribution (orientation: see [`envmap`]).
    Map(std::sync::Arc<EnvMap>),
}

/// Everything needed to render: geometry, appearance, lights and the view.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Where the scene came from (file path or "default"), used in logs and stats.
    pub name: String,
    pub mesh: Mesh,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub env: Environment,
    /// Lines for the log about what the loader skipped or changed ("warning: FILE: ..."),
    /// kept with the scene rather than printed, so that a file that then fails to load gets
    /// its one-line error alone.
    pub notes: Vec<String>,
    /// What read the scene and which conventions it follows.
    pub source: SceneSource,
}

/// Where a scene came from, recorded by its loader: the conventions it follows (which choose
/// the render's defaults, [`Settings::for_scene`](crate::settings::Settings::for_scene)) and
/// which reader parsed it (a fast reader may hand a file it cannot read to a general one;
/// the log, `info` and the stats show which ran, and the tests assert it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneSource {
    pub dialect: Dialect,
    /// The reader that parsed the file: "collada", "obj-bulk", "tobj", "ply-bulk",
    /// "ply-general", "gltf"; "embedded" for the default scene, "arrays" for a scene a
    /// caller built.
    pub reader: &'static str,
    /// The loader gave the scene the default sky because nothing in it emits light (see
    /// [`Scene::set_environment`]).
    pub default_sky: bool,
}

impl Default for SceneSource {
    /// A scene built from arrays: nothing asks for the CS184 conventions.
    fn default() -> Self {
        SceneSource { dialect: Dialect::Standard, reader: "arrays", default_sky: false }
    }
}

/// The light of a scene that nothing else lights: constant radiance 1 from the upper
/// hemisphere, a sky, so that a bare mesh file shows its shape.
pub const DEFAULT_SKY: Light = Light::Hemisphere { radiance: Vec3::ONE };

impl Scene {
    /// Whether anything lights the scene: a light, an emitting material or an environment.
    pub fn is_lit(&self) -> bool {
        !self.lights.is_empty()
            || self.materials.iter().any(|m| m.is_emissive())
            || !matches!(self.env, Environment::None)
    }

    /// Adds the default sky ([`DEFAULT_SKY`]) when nothing lights the scene, and records
    /// that it did ([`SceneSource::default_sky`]). The rule: the default sky only when the
    /// scene has no lights, no emitters and no environment.
    pub fn light_by_default_sky(&mut self) {
        if !self.is_lit() {
            self.lights.push(DEFAULT_SKY);
            self.source.default_sky = true;
        }
    }

    /// Replaces the environment, keeping the default sky's rule: an environment lights the
    /// scene, so the sky the loader added for want of light is taken away (a map given to a
    /// bare mesh is the light, not the map plus a sky); without one, an unlit scene gets the
    /// sky back.
    pub fn set_environment(&mut self, env: Environment) {
        if self.source.default_sky {
            if let Some(i) = self.lights.iter().position(|l| *l == DEFAULT_SKY) {
                self.lights.remove(i);
            }
            self.source.default_sky = false;
        }
        self.env = env;
        self.light_by_default_sky();
    }

    /// Frees the mesh's texture coordinates when no material has a decoded map of any kind
    /// to look up through them ([`Material::maps`]), since they are read for nothing else:
    /// 8 bytes a vertex of a scanned mesh that came with uvs.
    pub fn drop_unused_uvs(&mut self) {
        if !self.materials.iter().any(Material::reads_uvs) {
            self.mesh.uvs = None;
        }
    }

    /// Axis-aligned bounds of all geometry (triangles and spheres); `None` when there is none.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        use glam::Vec3A;
        use rayon::prelude::*;
        let empty = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let positions = &self.mesh.positions;
        // Parallel over chunks of triangles: only vertices that triangles use count. One
        // pair of bounds per corner, in SIMD registers, so that the min and max of tens of
        // millions of corners are three independent chains, not one.
        let (lo, hi) = self
            .mesh
            .triangles
            .par_chunks(1 << 16)
            .map(|c| {
                let corners = c.iter().fold([empty; 3], |mut acc, t| {
                    for (a, &i) in acc.iter_mut().zip(t) {
                        let p = Vec3A::from(positions[i as usize]);
                        *a = (a.0.min(p), a.1.max(p));
                    }
                    acc
                });
                corners.into_iter().fold(empty, |a, b| (a.0.min(b.0), a.1.max(b.1)))
            })
            .reduce(|| empty, |a, b| (a.0.min(b.0), a.1.max(b.1)));
        let (mut lo, mut hi) = (Vec3::from(lo), Vec3::from(hi));
        let mut any = !self.mesh.triangles.is_empty();
        for s in &self.spheres {
            lo = lo.min(s.center - Vec3::splat(s.radius));
            hi = hi.max(s.center + Vec3::splat(s.radius));
            any = true;
        }
        any.then_some((lo, hi))
    }

    /// Number of primitives an intersector sees: triangles first, then spheres.
    pub fn primitive_count(&self) -> usize {
        self.mesh.triangles.len() + self.spheres.len()
    }

    /// Checks the invariants every stage relies on; loaders call it last so that a bad
    /// file is reported at load time instead of producing NaN pixels later.
    pub fn validate(&self) -> Result<(), String> {
        self.mesh.validate(self.materials.len())?;
        for (i, s) in self.spheres.iter().enumerate() {
            if !s.center.is_finite() || !s.radius.is_finite() || s.radius <= 0.0 {
                return Err(format!("sphere {i} has a non-finite centre or a non-positive radius"));
            }
            if s.material as usize >= self.materials.len() {
                return Err(format!("sphere {i} refers to missing material {}", s.material));
            }
        }
        for (i, m) in self.materials.iter().enumerate() {
            m.validate().map_err(|e| format!("material {i} ({}): {e}", m.name))?;
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !light_is_finite(l) {
                return Err(format!("light {i} ({}) has non-finite parameters", l.kind()));
            }
        }
        self.camera.validate()?;
        Ok(())
    }
}

fn light_is_finite(l: &Light) -> bool {
    match *l {
        Light::Point { position, intensity, attenuation } => {
            position.is_finite() && intensity.is_finite() && attenuation.iter().all(|a| a.is_finite())
        }
        Light::Directional { direction, radiance } => {
            direction.is_finite() && direction.length_squared() > 0.0 && radiance.is_finite()
        }
        Light::Spot { position, direction, intensity, cone_angle, falloff_exponent } => {
            position.is_finite()
                && direction.is_finite()
                && intensity.is_finite()
                && cone_angle.is_finite()
                && falloff_exponent.is_finite()
        }
        Light::Hemisphere { radiance } => radiance.is_finite(),
        Light::Area { position, direction, dim_x, dim_y, radiance } => {
            position.is_finite()
                && direction.is_finite()
                && dim_x.is_finite()
                && dim_y.is_finite()
                && radiance.is_finite()
        }
    }
}
