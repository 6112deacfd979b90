//! The lane kernels' groups of data, one array per component (a lane loop over arrays of
//! structures is left scalar by the compiler): shading points and what they are rebuilt
//! from, rays with their weights, the emissive triangles and light samples a group picked.
//! Every lane kernel reads and writes its lanes through these.

#![allow(clippy::needless_range_loop)]

use crate::geometry::{Hit, Ray};
use crate::integrator::area::{AreaLight, LightRay, ShadingPoint, area_ray};
use crate::integrator::light_ray::LightPoint;
use crate::integrator::{Transport, orient};
use crate::lights::{Emitter, Infinite, SampledLight, Sky, SkySample};
use crate::scene::EnvMap;
use crate::scene::surface::{interpolated_normal, sphere_point, triangle_point};
use glam::Vec3;

/// Whether a kernel gathers whole vertices (`Transport::vertex`, one lane at a time): where
/// the surface has more than a position and normals to reconstruct. Elsewhere the kernels
/// reconstruct a group's points in lanes ([`surface_points`]).
#[inline(always)]
pub fn whole_vertices(t: &Transport) -> bool {
    t.materials.textures.any()
        || t.scene.mesh.colors.is_some()
        || t.materials.layers.any_relief
        || (t.rules.features.non_diffuse && t.materials.layers.volumes)
}

/// The shading points of a group, one array per component.
pub struct Points<const L: usize> {
    pub p: [[f32; L]; 3],
    pub e: [[f32; L]; 3],
    pub ng: [[f32; L]; 3],
    pub ns: [[f32; L]; 3],
    /// The ray hit the front of the surface (`orient`'s third value).
    pub front: [bool; L],
}

impl<const L: usize> Points<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, s: &ShadingPoint) {
        for (a, v) in [(&mut self.p, s.p), (&mut self.e, s.p_error), (&mut self.ng, s.ng), (&mut self.ns, s.ns)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
    }

    #[inline(always)]
    pub fn get(&self, j: usize) -> ShadingPoint {
        ShadingPoint { p: get(&self.p, j), p_error: get(&self.e, j), ng: get(&self.ng, j), ns: get(&self.ns, j) }
    }
}

impl<const L: usize> Default for Points<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Points { p: z, e: z, ng: z, ns: z, front: [false; L] }
    }
}

/// What the surface points of a group are reconstructed from: a triangle's corners (and
/// corner normals) and barycentrics, or a sphere and the ray's hit point on it.
pub struct Surfaces<const L: usize> {
    corner: [[[f32; L]; 3]; 3],
    normal: [[[f32; L]; 3]; 3],
    u: [f32; L],
    v: [f32; L],
    center: [[f32; L]; 3],
    radius: [f32; L],
    hit: [[f32; L]; 3],
    dir: [[f32; L]; 3],
    triangle: [bool; L],
}

impl<const L: usize> Default for Surfaces<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Surfaces {
            corner: [z; 3],
            normal: [z; 3],
            u: [0.0; L],
            v: [0.0; L],
            center: z,
            radius: [0.0; L],
            hit: z,
            dir: z,
            triangle: [false; L],
        }
    }
}

#[inline(always)]
pub fn put<const L: usize>(a: &mut [[f32; L]; 3], j: usize, v: Vec3) {
    a[0][j] = v.x;
    a[1][j] = v.y;
    a[2][j] = v.z;
}

#[inline(always)]
pub fn get<const L: usize>(a: &[[f32; L]; 3], j: usize) -> Vec3 {
    Vec3::new(a[0][j], a[1][j], a[2][j])
}

impl<const L: usize> Surfaces<L> {
    /// Gathers lane `j`'s hit (prim `prim`, on `ray`); `normals` is the mesh's corner
    /// normals, looked up once per stage rather than once per corner.
    #[inline(always)]
    pub fn set(&mut self, t: &Transport, normals: Option<&[Vec3]>, j: usize, ray: &Ray, hit: &Hit) {
        let mesh = &t.scene.mesh;
        let prim = hit.prim as usize;
        put(&mut self.dir, j, ray.dir);
        self.triangle[j] = prim < mesh.triangles.len();
        if self.triangle[j] {
            let ids = mesh.triangles[prim];
            for (k, &id) in ids.iter().enumerate() {
                put(&mut self.corner[k], j, mesh.positions[id as usize]);
            }
            if let Some(n) = normals {
                for (k, &id) in ids.iter().enumerate() {
                    put(&mut self.normal[k], j, n[id as usize]);
                }
            }
            (self.u[j], self.v[j]) = (hit.u, hit.v);
        } else {
            let s = &t.scene.spheres[prim - mesh.triangles.len()];
            put(&mut self.center, j, s.center);
            self.radius[j] = s.radius;
            put(&mut self.hit, j, ray.at(hit.t));
        }
    }

    /// Lane `j`'s shading point: both reconstructions (the same functions as
    /// `Scene::surface_point`), one kept, so all lanes run the same instructions; only the
    /// triangle's when the scene has no spheres (`SPHERES` false).
    #[inline(always)]
    fn point<const NORMALS: bool, const SPHERES: bool>(&self, j: usize) -> (ShadingPoint, bool) {
        let (u, v) = (self.u[j], self.v[j]);
        let c = &self.corner;
        let (tp, te, tn) = triangle_point(get(&c[0], j), get(&c[1], j), get(&c[2], j), u, v);
        let ts = if NORMALS {
            let n = &self.normal;
            interpolated_normal([get(&n[0], j), get(&n[1], j), get(&n[2], j)], u, v, tn)
        } else {
            tn
        };
        let (p, p_error, g, sh) = if SPHERES {
            let (sp, se, sn) = sphere_point(get(&self.center, j), self.radius[j], get(&self.hit, j));
            if self.triangle[j] { (tp, te, tn, ts) } else { (sp, se, sn, sn) }
        } else {
            (tp, te, tn, ts)
        };
        let (ng, ns, front) = orient(g, sh, get(&self.dir, j));
        (ShadingPoint { p, p_error, ng, ns }, front)
    }
}

/// Reconstructs the shading points of all lanes (lane-parallel).
#[inline(always)]
pub fn surface_points<const L: usize>(s: &Surfaces<L>, normals: bool, spheres: bool, out: &mut Points<L>) {
    // Plain loops, no closures: a closure may be compiled out of line, without AVX2.
    match (normals, spheres) {
        (true, true) => points_of::<true, true, L>(s, out),
        (true, false) => points_of::<true, false, L>(s, out),
        (false, true) => points_of::<false, true, L>(s, out),
        (false, false) => points_of::<false, false, L>(s, out),
    }
}

#[inline(always)]
fn points_of<const NORMALS: bool, const SPHERES: bool, const L: usize>(s: &Surfaces<L>, out: &mut Points<L>) {
    for j in 0..L {
        let (sp, front) = s.point::<NORMALS, SPHERES>(j);
        out.set(j, &sp);
        out.front[j] = front;
    }
}

/// A group's rays, one array per component.
pub struct Rays<const L: usize> {
    o: [[f32; L]; 3],
    d: [[f32; L]; 3],
    tmax: [f32; L],
    pub g: [f32; L],
    /// A light sample's whole weight, throughput not applied (one array per component, as
    /// everything a lane loop reads or writes: the compiler leaves a loop over arrays of
    /// structures scalar).
    w: [[f32; L]; 3],
    pub valid: [bool; L],
}

impl<const L: usize> Default for Rays<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Rays { o: z, d: z, tmax: [0.0; L], g: [0.0; L], w: z, valid: [false; L] }
    }
}

impl<const L: usize> Rays<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, r: &Ray) {
        for (a, v) in [(&mut self.o, r.origin), (&mut self.d, r.dir)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
        self.tmax[j] = r.tmax;
    }

    /// Lane `j`'s light sample: its ray, weight and validity.
    #[inline(always)]
    pub fn set_light_ray(&mut self, j: usize, r: &LightRay) {
        self.set(j, &r.ray);
        self.set_weight(j, r.weight);
        self.valid[j] = r.valid;
    }

    #[inline(always)]
    pub fn set_weight(&mut self, j: usize, w: Vec3) {
        put(&mut self.w, j, w);
    }

    #[inline(always)]
    pub fn weight(&self, j: usize) -> Vec3 {
        get(&self.w, j)
    }

    #[inline(always)]
    pub fn ray(&self, j: usize) -> Ray {
        Ray { origin: get(&self.o, j), dir: get(&self.d, j), tmin: 0.0, tmax: self.tmax[j] }
    }
}

/// `u` where `used`, else 0.5 (a lane whose sample is not taken computes on a harmless value).
#[inline(always)]
pub fn unused_half<const L: usize>(u: [f32; L], used: &[bool; L]) -> [f32; L] {
    let mut out = [0.5; L];
    for j in 0..L {
        if used[j] {
            out[j] = u[j];
        }
    }
    out
}

/// The shadow rays toward light `l` of all lanes (lane-parallel).
#[inline(always)]
pub fn area_rays<const L: usize>(pts: &Points<L>, l: &AreaLight, ua: &[f32; L], ub: &[f32; L], out: &mut Rays<L>) {
    for j in 0..L {
        let r = area_ray(&pts.get(j), l, ua[j], ub[j]);
        out.set(j, &r.ray);
        out.g[j] = r.g;
        out.valid[j] = r.valid;
    }
}

/// What [`triangle_ray`] reads of the emissive triangles a group's samples picked, one array
/// per component (a lane that picked none keeps an invalid one).
pub struct Emitters<const L: usize> {
    n: [[f32; L]; 3],
    inv_density: [f32; L],
    one_sided: [bool; L],
    valid: [bool; L],
}

impl<const L: usize> Default for Emitters<L> {
    fn default() -> Self {
        Emitters { n: [[0.0; L]; 3], inv_density: [0.0; L], one_sided: [false; L], valid: [false; L] }
    }
}

impl<const L: usize> Emitters<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, e: &Emitter) {
        put(&mut self.n, j, e.n);
        self.inv_density[j] = e.inv_density;
        self.one_sided[j] = e.one_sided;
        self.valid[j] = e.valid;
    }

    /// Lane `j`'s triangle as far as a sample's direction and density go (no corners).
    #[inline(always)]
    pub fn get(&self, j: usize) -> Emitter {
        Emitter {
            a: Vec3::ZERO,
            e1: Vec3::ZERO,
            e2: Vec3::ZERO,
            n: get(&self.n, j),
            valid: self.valid[j],
            inv_density: self.inv_density[j],
            one_sided: self.one_sided[j],
        }
    }
}

/// A group's samples of one light ([`LightPoint`]), one array per component.
#[derive(Clone, Copy)]
pub struct LightPoints<const L: usize> {
    wi: [[f32; L]; 3],
    weight: [[f32; L]; 3],
    pdf: [f32; L],
    target: [[f32; L]; 3],
    finite: [bool; L],
    valid: [bool; L],
}

impl<const L: usize> Default for LightPoints<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        LightPoints { wi: z, weight: z, pdf: [0.0; L], target: z, finite: [false; L], valid: [false; L] }
    }
}

impl<const L: usize> LightPoints<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, l: &LightPoint) {
        put(&mut self.wi, j, l.wi);
        put(&mut self.weight, j, l.weight);
        self.pdf[j] = l.pdf;
        put(&mut self.target, j, l.target);
        self.finite[j] = l.finite;
        self.valid[j] = l.valid;
    }

    #[inline(always)]
    pub fn get(&self, j: usize) -> LightPoint {
        LightPoint {
            wi: get(&self.wi, j),
            weight: get(&self.weight, j),
            pdf: self.pdf[j],
            target: get(&self.target, j),
            finite: self.finite[j],
            valid: self.valid[j],
        }
    }

    /// The samples of the light from infinity without a map for every lane in `take` about
    /// the normals `n`, from the numbers `(ua, ub)`: all lanes at once
    /// ([`Sky::sample_cosine`]); the density is the one MIS reads.
    #[inline(always)]
    pub fn sky(inf: Sky, n: &[[f32; L]; 3], ua: &[f32; L], ub: &[f32; L], take: &[bool; L]) -> Self {
        let mut out = LightPoints::default();
        for j in 0..L {
            let n = get(n, j);
            let (wi, weight, valid) = inf.sample_cosine(n, [ua[j], ub[j]]);
            let pdf = inf.pdf_with(n, wi, 0.0, false);
            out.set(j, &LightPoint { wi, weight, pdf, target: Vec3::ZERO, finite: false, valid: valid & take[j] });
        }
        out
    }
}

impl<const L: usize> LightPoints<L> {
    /// The samples of the light from infinity with an environment map (`inf`, its map `map`)
    /// for every lane in `take` about the normals `n`, from `(ua, ub)` (the density kept where
    /// `mis`), as
    /// [`Infinite::sample_pdf`] computes them one at a time: the map's table read for every
    /// lane first, then the texels drawn (independent loads the core overlaps), then the directions, densities and
    /// weights of all lanes in one loop that vectorises ([`Sky::drawn`]); a mixture with
    /// the constant sky also looks the map up toward each chosen direction (the texel
    /// indices in lanes, the reads, then [`Sky::mixed`] in lanes).
    #[inline(always)]
    pub fn environment(
        inf: &Infinite,
        map: &EnvMap,
        n: &[[f32; L]; 3],
        ua: &[f32; L],
        ub: &[f32; L],
        mis: &[bool; L],
        take: &[bool; L],
    ) -> Self {
        let sky = inf.sky();
        let mut uv = [[0.0f32; L]; 2];
        let mut index = [usize::MAX; L];
        for j in 0..L {
            if take[j] {
                let (c, i) = map.draw(sky.map_numbers([ua[j], ub[j]]));
                (uv[0][j], uv[1][j], index[j]) = (c[0], c[1], i);
            }
        }
        let mut pdf_uv = [0.0f32; L];
        let mut texel = [[0.0f32; L]; 3];
        for j in 0..L {
            if take[j] {
                let (l, p) = map.texel_at(index[j]);
                put(&mut texel, j, l);
                pdf_uv[j] = p;
            }
        }
        let mut drawn = [SkySample { wi: Vec3::ZERO, weight: Vec3::ZERO, pdf: 0.0, valid: false }; L];
        for j in 0..L {
            drawn[j] = sky.drawn(get(n, j), [ua[j], ub[j]], [uv[0][j], uv[1][j]], pdf_uv[j], get(&texel, j));
        }
        if !sky.map_alone() {
            let mut index = [0usize; L];
            let mut sin_theta = [0.0f32; L];
            for j in 0..L {
                (index[j], sin_theta[j]) = map.index_of(drawn[j].wi);
            }
            let mut mapped = [[0.0f32; L]; 3];
            let mut mapped_pdf = [0.0f32; L];
            for j in 0..L {
                if take[j] {
                    let (l, p) = map.at_index(index[j], sin_theta[j]);
                    put(&mut mapped, j, l);
                    mapped_pdf[j] = p;
                }
            }
            for j in 0..L {
                drawn[j] = sky.mixed(get(n, j), drawn[j], get(&mapped, j), mapped_pdf[j]);
            }
        }
        let mut out = LightPoints::default();
        for j in 0..L {
            let s = drawn[j];
            let valid = s.valid & take[j];
            let pdf = if mis[j] { s.pdf } else { 0.0 };
            out.set(j, &LightPoint { wi: s.wi, weight: s.weight, pdf, target: Vec3::ZERO, finite: false, valid });
        }
        out
    }

    /// The samples of a point, spot or directional light (`SampledLight::sample`, and
    /// `sample_pdf`'s infinite density where `mis`) at the points `p` of every lane in `take`:
    /// all lanes at once, the same operations lane by lane (`try_normalize` spelled out; a
    /// spot's `powf` one lane at a time); `None` for any other light.
    #[inline(always)]
    pub fn delta(light: &SampledLight, p: &[[f32; L]; 3], mis: &[bool; L], take: &[bool; L]) -> Option<Self> {
        let (position, intensity, spot) = match *light {
            SampledLight::Point { position, intensity } => (position, intensity, None),
            SampledLight::Spot { position, axis, cos_cutoff, exponent, intensity } => {
                (position, intensity, Some((axis, cos_cutoff, exponent)))
            }
            SampledLight::Directional { to_light, radiance } => {
                let mut out = LightPoints::default();
                for j in 0..L {
                    let pdf = if mis[j] { f32::INFINITY } else { 0.0 };
                    let l = LightPoint {
                        wi: to_light,
                        weight: radiance,
                        pdf,
                        target: Vec3::ZERO,
                        finite: false,
                        valid: take[j],
                    };
                    out.set(j, &l);
                }
                return Some(out);
            }
            _ => return None,
        };
        let mut out = LightPoints::default();
        let mut cos = [0.0f32; L];
        for j in 0..L {
            let d = position - get(p, j);
            let rcp = d.length_recip();
            let wi = d * rcp;
            let mut valid = take[j] & rcp.is_finite() & (rcp > 0.0);
            if let Some((axis, cos_cutoff, _)) = spot {
                cos[j] = (-wi).dot(axis);
                // As `sample`'s rejection (`c < cos_cutoff`), NaN included.
                let outside = cos[j] < cos_cutoff;
                valid &= !outside;
            }
            let pdf = if mis[j] { f32::INFINITY } else { 0.0 };
            out.set(j, &LightPoint { wi, weight: intensity, pdf, target: position, finite: true, valid });
        }
        if let Some((_, _, exponent)) = spot
            && exponent > 0.0
        {
            for j in 0..L {
                if out.valid[j] {
                    put(&mut out.weight, j, intensity * cos[j].max(0.0).powf(exponent));
                }
            }
        }
        Some(out)
    }
}
