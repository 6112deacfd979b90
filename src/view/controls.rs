//! What a client may ask of the viewer, parsed from `key=value` pairs and checked against
//! bounds before anything changes: a bad value is a message for a 400, never a panic and
//! never a render with absurd settings. The render settings are checked by the engine
//! (`wavepath::Field`, `wavepath::Shading`'s names), so a value the command line or Python
//! refuses is refused here with the same message, under the control's name.

use wavepath::{Aov, Field, Shading};

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
    /// What the image shows: the picture (`None`) or one output variable of the same render.
    Show(Option<Aov>),
    /// Denoise the picture's frames (refused by the server when it has no denoiser).
    Denoise(bool),
}

/// `show`'s name for the picture itself.
pub const PICTURE: &str = "picture";

/// The picture or the output variable named `v` (`show=`).
fn show(v: &str) -> Result<Option<Aov>, String> {
    if v.trim().eq_ignore_ascii_case(PICTURE) {
        return Ok(None);
    }
    v.parse::<Aov>().map(Some).map_err(|e| {
        let names: Vec<&str> = std::iter::once(PICTURE).chain(e.names().iter().copied()).collect();
        let (last, rest) = names.split_last().expect("names");
        format!("show must be {} or {last}, got '{v}'", rest.join(", "))
    })
}

/// The name `show=` takes for `aov` (`None`: the picture).
pub fn show_name(aov: Option<Aov>) -> &'static str {
    aov.map_or(PICTURE, Aov::name)
}

/// Largest image side a client may ask for: below the engine's limit, since the viewer
/// keeps a canvas of the whole image and encodes it several times a second.
pub const MAX_SIDE: usize = 4096;

/// The viewer's name for each render value it takes (its controls' keys).
pub fn control(f: Field) -> &'static str {
    match f {
        Field::Width | Field::Height => "res",
        Field::Spp => "spp",
        Field::LightSamples => "l",
        Field::MaxDepth => "m",
        Field::ContinueProb => "rr",
        Field::LensRadius => "lens",
        Field::FocalDistance => "focal",
        _ => "?",
    }
}

/// A whole-number render value, checked by the engine.
fn setting(f: Field, v: &str) -> Result<u32, String> {
    let key = control(f);
    let x: i64 = v.trim().parse().map_err(|_| format!("{key}: '{v}' is not a whole number"))?;
    f.whole(key, x).map_err(|e| e.to_string())
}

/// A real render value, checked by the engine.
fn real_setting(f: Field, v: &str) -> Result<f32, String> {
    let key = control(f);
    let x: f64 = v.trim().parse().map_err(|_| format!("{key}: '{v}' is not a number"))?;
    f.number(key, x).map(|x| x as f32).map_err(|e| e.to_string())
}

/// `WxH`, within the engine's limits and the viewer's own side.
fn resolution(v: &str) -> Result<(usize, usize), String> {
    let key = control(Field::Width);
    let (w, h) = v.split_once('x').ok_or_else(|| format!("{key}: expected WxH, got '{v}'"))?;
    let whole = |t: &str| t.trim().parse::<i64>().map_err(|_| format!("{key}: '{t}' is not a whole number"));
    let (w, h) = wavepath::check_resolution(key, whole(w)?, whole(h)?).map_err(|e| e.to_string())?;
    if w.max(h) > MAX_SIDE {
        return Err(format!("{key} {w}x{h} is larger than the viewer's {MAX_SIDE}x{MAX_SIDE}"));
    }
    Ok((w, h))
}

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
        "spp" => Change::Spp(setting(Field::Spp, v)?),
        "l" => Change::LightSamples(setting(Field::LightSamples, v)?),
        "m" => Change::MaxDepth(setting(Field::MaxDepth, v)?),
        "shading" => Change::Shading(v.parse::<Shading>().map_err(|e| e.for_option(key).to_string())?),
        "rr" => Change::Roulette(real_setting(Field::ContinueProb, v)?),
        "hemisphere" => Change::Hemisphere(flag(key, v)?),
        "lens" => Change::LensRadius(real_setting(Field::LensRadius, v)?),
        "focal" => Change::FocalDistance(real_setting(Field::FocalDistance, v)?),
        "env" => Change::Environment(flag(key, v)?),
        "bvh" => Change::BvhDepth(match v {
            "off" | "-1" => None,
            _ => Some(whole(key, v, 0, 32)?),
        }),
        "res" => {
            let (w, h) = resolution(v)?;
            Change::Resolution(w, h)
        }
        "show" => Change::Show(show(v)?),
        "denoise" => Change::Denoise(flag(key, v)?),
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
    use wavepath::Choice;

    #[test]
    fn values_are_bounded_and_non_numbers_refused() {
        assert_eq!(parse("orbit", "0.1,-0.2"), Ok(Change::Orbit(0.1, -0.2)));
        assert_eq!(parse_query("spp=64&m=5&shading=direct").unwrap().len(), 3);
        assert_eq!(parse("res", "640x480"), Ok(Change::Resolution(640, 480)));
        assert_eq!(parse("bvh", "off"), Ok(Change::BvhDepth(None)));
        assert_eq!(parse("show", "picture"), Ok(Change::Show(None)));
        assert_eq!(parse("show", "Normal"), Ok(Change::Show(Some(Aov::Normal))));
        assert_eq!(parse("denoise", "1"), Ok(Change::Denoise(true)));
        for a in Aov::ALL {
            assert_eq!(parse("show", a.name()), Ok(Change::Show(Some(*a))));
        }
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
            ("res", "5000x10"),
            ("focal", "-1"),
            ("focus", "2,0.5"),
            ("hemisphere", "maybe"),
            ("shading", "wireframe"),
            ("show", "beauty"),
            ("denoise", "yes"),
            ("rm -rf", "/"),
        ] {
            let e = parse(k, v).unwrap_err();
            assert!(e.contains(k.split(' ').next().unwrap()) || e.contains("unknown"), "{k}={v}: {e}");
        }
        assert!(parse_query("").is_err() && parse_query(&"a".repeat(5000)).is_err());
    }

    /// The render values are checked by the engine: the command line's and Python's message
    /// under the control's name (tests/it compares them with the binary's).
    #[test]
    fn render_values_get_the_engines_messages() {
        let refused = |k: &str, v: &str| parse(k, v).unwrap_err();
        assert_eq!(refused("spp", "0"), "spp (samples per pixel) must be between 1 and 1048576, got 0");
        assert_eq!(refused("res", "0x10"), "res (image width) must be between 1 and 32768, got 0");
        assert_eq!(refused("res", "10x100000"), "res (image height) must be between 1 and 32768, got 100000");
        assert_eq!(refused("rr", "1.5"), "rr (continue probability) must be in (0, 1], got 1.5");
        assert_eq!(refused("shading", "wireframe"), "shading must be normals, direct or global, got 'wireframe'");
        for (k, v, field) in [("spp", 0, Field::Spp), ("m", -1, Field::MaxDepth), ("l", 0, Field::LightSamples)] {
            assert_eq!(refused(k, &v.to_string()), field.whole(k, v).unwrap_err().to_string());
        }
        assert_eq!(
            refused("show", "beauty"),
            "show must be picture, albedo, normal, depth, position or variance, got 'beauty'"
        );
        // The viewer's own limit, below the engine's.
        assert_eq!(refused("res", "5000x10"), "res 5000x10 is larger than the viewer's 4096x4096");
    }
}
