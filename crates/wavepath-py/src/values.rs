//! Materials, lights, spheres and cameras as plain Python values (dicts with a `"type"`),
//! so that a scene can be written in a few lines without classes to import. Every key is
//! checked: a misspelt one is an error, not a silently ignored setting.

use crate::errors::value_error;
use glam::Vec3;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use wavepath::{Bsdf, Camera, Light, Material, Sphere};

/// One dict being read: its entries, what is read of them, and a name for messages.
struct Entries<'py> {
    dict: Bound<'py, PyDict>,
    what: String,
    known: Vec<&'static str>,
}

impl<'py> Entries<'py> {
    fn new(obj: &Bound<'py, PyAny>, what: String) -> PyResult<Self> {
        let dict = obj.cast::<PyDict>().map_err(|_| value_error(format!("{what} must be a dict")))?.clone();
        Ok(Entries { dict, what, known: vec!["type"] })
    }

    fn kind(&self) -> PyResult<String> {
        match self.dict.get_item("type")? {
            Some(t) => {
                t.extract::<String>().map_err(|_| value_error(format!("{}: \"type\" must be a string", self.what)))
            }
            None => Err(value_error(format!("{} has no \"type\"", self.what))),
        }
    }

    fn get(&mut self, key: &'static str) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.known.push(key);
        self.dict.get_item(key)
    }

    fn vec3(&mut self, key: &'static str, default: Option<Vec3>) -> PyResult<Vec3> {
        let what = self.what.clone();
        match self.get(key)? {
            Some(v) => {
                let v = if let Ok(x) = v.extract::<f32>() {
                    Vec3::splat(x)
                } else {
                    let a: [f32; 3] = v
                        .extract()
                        .map_err(|_| value_error(format!("{what}: \"{key}\" must be a number or three numbers")))?;
                    Vec3::from(a)
                };
                if !v.is_finite() {
                    return Err(value_error(format!("{what}: \"{key}\" is not finite")));
                }
                Ok(v)
            }
            None => default.ok_or_else(|| value_error(format!("{what} needs \"{key}\""))),
        }
    }

    fn number(&mut self, key: &'static str, default: Option<f32>) -> PyResult<f32> {
        let what = self.what.clone();
        match self.get(key)? {
            Some(v) => {
                let x: f32 = v.extract().map_err(|_| value_error(format!("{what}: \"{key}\" must be a number")))?;
                if !x.is_finite() {
                    return Err(value_error(format!("{what}: \"{key}\" is not finite")));
                }
                Ok(x)
            }
            None => default.ok_or_else(|| value_error(format!("{what} needs \"{key}\""))),
        }
    }

    fn flag(&mut self, key: &'static str, default: bool) -> PyResult<bool> {
        let what = self.what.clone();
        match self.get(key)? {
            Some(v) => v.extract().map_err(|_| value_error(format!("{what}: \"{key}\" must be True or False"))),
            None => Ok(default),
        }
    }

    fn text(&mut self, key: &'static str) -> PyResult<Option<String>> {
        let what = self.what.clone();
        match self.get(key)? {
            Some(v) => Ok(Some(v.extract().map_err(|_| value_error(format!("{what}: \"{key}\" must be a string")))?)),
            None => Ok(None),
        }
    }

    /// Fails on any key that was not read.
    fn done(self) -> PyResult<()> {
        for (k, _) in self.dict.iter() {
            let k: String = k.extract().unwrap_or_else(|_| "?".into());
            if !self.known.contains(&k.as_str()) {
                return Err(value_error(format!(
                    "{}: unknown key \"{k}\" (known: {})",
                    self.what,
                    self.known.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// A material dict: `{"type": "diffuse", "color": (r, g, b)}`; also `emitter`, `mirror`,
/// `glass`, `metallic_roughness`, `phong`. Any type takes `"emission"`, `"two_sided"` and
/// `"name"`.
pub fn material(obj: &Bound<'_, PyAny>, i: usize) -> PyResult<Material> {
    let mut e = Entries::new(obj, format!("materials[{i}]"))?;
    let kind = e.kind()?;
    let name = e.text("name")?.unwrap_or_else(|| format!("{kind} {i}"));
    let mut m = match kind.as_str() {
        "diffuse" => Material::diffuse(&name, e.vec3("color", Some(Vec3::splat(0.5)))?),
        "emitter" => Material::emitter(&name, e.vec3("radiance", None)?),
        "mirror" => Material {
            bsdf: Bsdf::Mirror { reflectance: e.vec3("color", Some(Vec3::ONE))? },
            ..Material::diffuse(&name, Vec3::ZERO)
        },
        "glass" => Material {
            bsdf: Bsdf::Glass {
                reflectance: e.vec3("reflectance", Some(Vec3::ONE))?,
                transmittance: e.vec3("color", Some(Vec3::ONE))?,
                roughness: e.number("roughness", Some(0.0))?,
                ior: e.number("ior", Some(1.5))?,
            },
            ..Material::diffuse(&name, Vec3::ZERO)
        },
        "metallic_roughness" => Material {
            bsdf: Bsdf::MetallicRoughness {
                base: e.vec3("color", Some(Vec3::splat(0.5)))?,
                metallic: e.number("metallic", Some(0.0))?,
                roughness: e.number("roughness", Some(0.5))?,
            },
            ..Material::diffuse(&name, Vec3::ZERO)
        },
        "phong" => Material {
            bsdf: Bsdf::Phong {
                diffuse: e.vec3("diffuse", Some(Vec3::splat(0.5)))?,
                specular: e.vec3("specular", Some(Vec3::splat(0.04)))?,
                shininess: e.number("shininess", Some(32.0))?,
            },
            ..Material::diffuse(&name, Vec3::ZERO)
        },
        other => {
            return Err(value_error(format!(
                "materials[{i}]: unknown type \"{other}\" (diffuse, emitter, mirror, glass, metallic_roughness, phong)"
            )));
        }
    };
    if kind != "emitter" {
        m.emission = e.vec3("emission", Some(Vec3::ZERO))?;
    }
    if m.emission.min_element() < 0.0 {
        return Err(value_error(format!("materials[{i}]: negative emission")));
    }
    // Emitters of meshes given as arrays emit from the front, as OBJ's and glTF's do,
    // unless told otherwise.
    m.two_sided_emission = e.flag("two_sided", false)?;
    e.done()?;
    Ok(m)
}

/// A light dict: `point`, `directional`, `spot`, `area` or `sky`.
pub fn light(obj: &Bound<'_, PyAny>, i: usize) -> PyResult<Light> {
    let mut e = Entries::new(obj, format!("lights[{i}]"))?;
    let kind = e.kind()?;
    let l = match kind.as_str() {
        "point" => Light::Point {
            position: e.vec3("position", None)?,
            intensity: e.vec3("intensity", None)?,
            attenuation: [1.0, 0.0, 0.0],
        },
        "directional" => {
            Light::Directional { direction: e.vec3("direction", None)?, radiance: e.vec3("radiance", None)? }
        }
        "spot" => Light::Spot {
            position: e.vec3("position", None)?,
            direction: e.vec3("direction", None)?,
            intensity: e.vec3("intensity", None)?,
            cone_angle: e.number("angle", Some(45.0))?,
            falloff_exponent: e.number("falloff", Some(0.0))?,
        },
        "area" => Light::Area {
            position: e.vec3("position", None)?,
            direction: e.vec3("direction", None)?,
            dim_x: e.vec3("size_x", None)?,
            dim_y: e.vec3("size_y", None)?,
            radiance: e.vec3("radiance", None)?,
        },
        "sky" => Light::Hemisphere { radiance: e.vec3("radiance", Some(Vec3::ONE))? },
        other => {
            return Err(value_error(format!(
                "lights[{i}]: unknown type \"{other}\" (point, directional, spot, area, sky)"
            )));
        }
    };
    e.done()?;
    Ok(l)
}

/// A sphere dict: `{"center": (x, y, z), "radius": r, "material": i}`.
pub fn sphere(obj: &Bound<'_, PyAny>, i: usize) -> PyResult<Sphere> {
    let mut e = Entries::new(obj, format!("spheres[{i}]"))?;
    e.known.clear();
    let center = e.vec3("center", None)?;
    let radius = e.number("radius", None)?;
    let material = e.number("material", Some(0.0))?;
    e.done()?;
    if material < 0.0 || material.fract() != 0.0 {
        return Err(value_error(format!("spheres[{i}]: \"material\" must be a material index")));
    }
    Ok(Sphere { center, radius, material: material as u32 })
}

/// A camera: a dict `{"eye": .., "target": .., "up": (0, 1, 0), "fov": 45}` (vertical
/// field of view in degrees), or the path of a camera file (`wavepath` view's `c` key
/// writes them).
pub fn camera(obj: &Bound<'_, PyAny>) -> PyResult<Camera> {
    if let Ok(path) = obj.extract::<std::path::PathBuf>()
        && obj.cast::<PyDict>().is_err()
    {
        return wavepath::read_camera_file(&path).map_err(crate::errors::to_py);
    }
    let mut e = Entries::new(obj, "camera".into())?;
    e.known.clear();
    let eye = e.vec3("eye", None)?;
    let target = e.vec3("target", None)?;
    let up = e.vec3("up", Some(Vec3::Y))?;
    let fov = e.number("fov", Some(45.0))?;
    let lens_radius = e.number("lens_radius", Some(0.0))?;
    let focal = e.get("focal_distance")?.map(|v| v.extract::<f32>()).transpose()?;
    e.done()?;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(value_error(format!("camera: \"fov\" must be between 0 and 180 degrees, got {fov}")));
    }
    if (eye - target).length_squared() == 0.0 {
        return Err(value_error("camera: \"eye\" and \"target\" are the same point"));
    }
    let mut c = Camera::look_at(eye, target, up, fov, 4.0 / 3.0);
    c.lens_radius = lens_radius;
    if let Some(f) = focal {
        c.focal_distance = f;
    }
    c.validate().map_err(|m| value_error(format!("camera: {m}")))?;
    Ok(c)
}
