//! What a client may ask of the viewer, parsed from `key=value` pairs and checked against
//! bounds before anything changes: a bad value is a message for a 400, never a panic and
//! never a render with absurd settings.

use wavepath::Shading;

/// One change a client asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// Turn about the target by (yaw, pitch) radians.
    Orbit(f32, f32),
    /// Move camera and target by (dx, dy) times the distance to the target.
    Pan(f32, f32),
    /// Multiply the distance to the target.
    Zoom(f32),
    /// Back to the file's camera.
    Reset,
    /// Focus the thin lens on what the image point (x, y) in [0, 1]^2 (top-left origin) sees.
    Focus(f32, f32),
    /// Samples per pixel the render stops at.
    Spp(u32),
    LightSamples(u32),
    MaxDepth(u32),
    Shading(Shading),
    /// Fixed Russian roulette continue probability.
    Roulette(f32),
    /// Uniform hemisphere sampling for direct light (`-H`).
    Hemisphere(bool),
    LensRadius(f32),
    FocalDistance(f32),
    Environment(bool),
    /// The BVH view: outline the boxes at this depth (`None`: off).
    BvhDepth(Option<u32>),
    Resolution(usize, usize),
}

/// Largest image side a client may ask for.
pub const MAX_SIDE: usize = 4096;
/// Largest samples-per-pixel cap.
pub const MAX_SPP: u32 = 1 << 16;

fn number(key: &str, v: &str) -> Result<f32, String> {
    let x: f32 = v.trim().parse().map_err(|_| format!("{key}: '{v}' is not a number"))?;
    if x.is_finite() { Ok(x) } else { Err(format!("{key}: '{v}' is not a finite number")) }
}

fn whole(key: &str, v: &str, lo: u32, hi: u32) -> Result<u32, String> {
    let x: u32 = v.trim().parse().map_err(|_| format!("{key}: '{v}' is not a whole number"))?;
    if (lo..=hi).contains(&x) { Ok(x) } else { Err(format!("{key}: {x} is outside {lo}..={hi}")) }
}

fn bounded(key: &str, v: &str, lo: f32, hi: f32) -> Result<f32, String> {
    let x = number(key, v)?;
    if (lo..=hi).contains(&x) { Ok(x) } else { Err(format!("{key}: {x} is outside [{lo}, {hi}]")) }
}

/// A number in (0, `hi`].
fn positive(key: &str, v: &str, hi: f32) -> Result<f32, String> {
    let x = bounded(key, v, 0.0, hi)?;
    if x > 0.0 { Ok(x) } else { Err(format!("{key}: must be above 0")) }
}

fn pair(key: &str, v: &str, limit: f32) -> Result<(f32, f32), String> {
    let (a, b) = v.split_once(',').ok_or_else(|| format!("{key}: expected two numbers 'a,b', got '{v}'"))?;
    Ok((bounded(key, a, -limit, limit)?, bounded(key, b, -limit, limit)?))
}

fn flag(key: &str, v: &str) -> Result<bool, String> {
    match v {
        "1" | "true" | "on" => Ok(true),
        "0" | "false" | "off" => Ok(false),
        _ => Err(format!("{key}: expected 0 or 1, got '{v}'")),
    }
}

/// The change `key=value` asks for.
pub fn parse(key: &str, v: &str) -> Result<Change, String> {
    Ok(match key {
        "orbit" => {
            let (a, b) = pair(key, v, 10.0)?;
            Change::Orbit(a, b)
        }
        "pan" => {
            let (a, b) = pair(key, v, 10.0)?;
            Change::Pan(a, b)
        }
        "zoom" => Change::Zoom(bounded(key, v, 0.01, 100.0)?),
        "reset" => Change::Reset,
        "focus" => {
            let (x, y) = pair(key, v, 1.0)?;
            if x < 0.0 || y < 0.0 {
                return Err(format!("focus: ({x}, {y}) is outside the image"));
            }
            Change::Focus(x, y)
        }
        "spp" => Change::Spp(whole(key, v, 1, MAX_SPP)?),
        "l" => Change::LightSamples(whole(key, v, 1, 1024)?),
        "m" => Change::MaxDepth(whole(key, v, 1, 64)?),
        "shading" => Change::Shading(match v {
            "normals" => Shading::Normals,
            "direct" => Shading::Direct,
            "global" => Shading::Global,
            _ => return Err(format!("shading: expected normals, direct or global, got '{v}'")),
        }),
        "rr" => Change::Roulette(positive(key, v, 1.0)?),
        "hemisphere" => Change::Hemisphere(flag(key, v)?),
        "lens" => Change::LensRadius(bounded(key, v, 0.0, 1e6)?),
        "focal" => Change::FocalDistance(positive(key, v, 1e9)?),
        "env" => Change::Environment(flag(key, v)?),
        "bvh" => Change::BvhDepth(match v {
            "off" | "-1" => None,
            _ => Some(whole(key, v, 0, 32)?),
        }),
        "res" => {
            let (w, h) = v.split_once('x').ok_or_else(|| format!("res: expected WxH, got '{v}'"))?;
            let (w, h) = (whole(key, w, 1, MAX_SIDE as u32)?, whole(key, h, 1, MAX_SIDE as u32)?);
            Change::Resolution(w as usize, h as usize)
        }
        _ => return Err(format!("unknown control '{key}'")),
    })
}

/// Every `key=value` pair of a query string (`a=1&b=2`), percent-decoded, parsed; the first
/// bad one is the error.
pub fn parse_query(query: &str) -> Result<Vec<Change>, String> {
    if query.len() > 4096 {
        return Err("query longer than 4096 bytes".into());
    }
    let mut out = Vec::new();
    for part in query.split('&').filter(|p| !p.is_empty()) {
        let (k, v) = part.split_once('=').unwrap_or((part, ""));
        let v = urlencoding::decode(v).map_err(|_| format!("{k}: value is not UTF-8"))?;
        out.push(parse(k, &v)?);
    }
    if out.is_empty() {
        return Err("no control given (e.g. /control?spp=64)".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_bounded_and_non_numbers_refused() {
        assert_eq!(parse("orbit", "0.1,-0.2"), Ok(Change::Orbit(0.1, -0.2)));
        assert_eq!(parse_query("spp=64&m=5&shading=direct").unwrap().len(), 3);
        assert_eq!(parse("res", "640x480"), Ok(Change::Resolution(640, 480)));
        assert_eq!(parse("bvh", "off"), Ok(Change::BvhDepth(None)));
        for (k, v) in [
            ("spp", "0"),
            ("spp", "1e9"),
            ("spp", "abc"),
            ("m", "-1"),
            ("orbit", "NaN,0"),
            ("orbit", "1"),
            ("zoom", "inf"),
            ("zoom", "0"),
            ("rr", "0"),
            ("res", "0x10"),
            ("res", "100000x10"),
            ("focal", "-1"),
            ("focus", "2,0.5"),
            ("hemisphere", "maybe"),
            ("shading", "wireframe"),
            ("rm -rf", "/"),
        ] {
            let e = parse(k, v).unwrap_err();
            assert!(e.contains(k.split(' ').next().unwrap()) || e.contains("unknown"), "{k}={v}: {e}");
        }
        assert!(parse_query("").is_err() && parse_query(&"a".repeat(5000)).is_err());
    }
}
