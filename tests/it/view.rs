//! `wavepath view` driven as a user drives it: the binary serves on a free port; these tests
//! speak HTTP to it (plain sockets), change the camera and settings, read frames, compare the
//! converged image with the offline render of the same samples, run the command it gives,
//! send it bad input, and stop it with Ctrl-C; it shows each output variable and, with Open
//! Image Denoise, the denoised picture. The browser test opens the page in headless Chromium
//! and drives it through the DevTools protocol.

use crate::common::{temp_dir, wavepath_bin};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running `wavepath view` and its address.
struct View {
    child: Child,
    addr: String,
}

impl View {
    fn start(args: &[&str]) -> View {
        View::start_with(args, &[])
    }

    /// As [`start`](Self::start), with these environment variables.
    fn start_with(args: &[&str], env: &[(&str, &str)]) -> View {
        let mut child = Command::new(wavepath_bin())
            .arg("view")
            .args(args)
            .envs(env.iter().copied())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("wavepath runs");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let addr = line.trim().trim_start_matches("http://").trim_end_matches('/').to_string();
        assert!(addr.starts_with("127.0.0.1:"), "first line: {line:?}");
        View { child, addr }
    }

    /// (status, headers, body) of one request.
    fn request(&self, method: &str, path: &str) -> (u16, String, Vec<u8>) {
        let mut s = TcpStream::connect(&self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        write!(s, "{method} {path} HTTP/1.1\r\nHost: {}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n", self.addr)
            .unwrap();
        let mut raw = Vec::new();
        s.read_to_end(&mut raw).unwrap();
        let split = raw.windows(4).position(|w| w == b"\r\n\r\n").expect("a header block");
        let head = String::from_utf8_lossy(&raw[..split]).to_string();
        let status = head.split(' ').nth(1).unwrap().parse().unwrap();
        let mut body = raw[split + 4..].to_vec();
        if head.to_ascii_lowercase().contains("transfer-encoding: chunked") {
            body = dechunk(&body);
        }
        (status, head, body)
    }

    fn get(&self, path: &str) -> (u16, Vec<u8>) {
        let (s, _, b) = self.request("GET", path);
        (s, b)
    }

    fn post(&self, path: &str) -> (u16, String) {
        let (s, _, b) = self.request("POST", path);
        (s, String::from_utf8_lossy(&b).into_owned())
    }

    /// An open `/events` stream.
    fn events(&self) -> BufReader<TcpStream> {
        let mut s = TcpStream::connect(&self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        write!(s, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
        BufReader::new(s)
    }

    /// Waits (up to 60 s) for a frame of generation `generation` or later that `done` accepts.
    fn wait(&self, generation: u64, done: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let t = Instant::now();
        loop {
            if let (200, b) = self.get("/info") {
                let v: serde_json::Value = serde_json::from_slice(&b).unwrap();
                if v["generation"].as_u64().unwrap() >= generation && done(&v) {
                    return v;
                }
            }
            assert!(t.elapsed() < Duration::from_secs(60), "no such frame within 60 s");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Ctrl-C; the process must end by itself, successfully.
    fn interrupt(mut self) -> String {
        Command::new("kill").args(["-INT", &self.child.id().to_string()]).status().unwrap();
        let t = Instant::now();
        while self.child.try_wait().unwrap().is_none() {
            assert!(t.elapsed() < Duration::from_secs(10), "still running 10 s after Ctrl-C");
            std::thread::sleep(Duration::from_millis(20));
        }
        let status = self.child.wait().unwrap();
        let mut err = String::new();
        self.child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
        assert!(status.success(), "exit {status}: {err}");
        err
    }
}

impl Drop for View {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let Some(eol) = b.windows(2).position(|w| w == b"\r\n") else { return out };
        let n = usize::from_str_radix(String::from_utf8_lossy(&b[..eol]).trim(), 16).unwrap_or(0);
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + n]);
        b = &b[eol + 4 + n..];
    }
}

/// The next frame event of a stream.
fn next_frame(s: &mut BufReader<TcpStream>) -> serde_json::Value {
    let mut line = String::new();
    loop {
        line.clear();
        assert!(s.read_line(&mut line).unwrap() > 0, "stream closed");
        if let Some(data) = line.strip_prefix("data: ") {
            return serde_json::from_str(data).unwrap();
        }
    }
}

fn generation(reply: &str) -> u64 {
    reply.trim().strip_prefix("generation ").and_then(|g| g.parse().ok()).unwrap_or_else(|| panic!("{reply}"))
}

/// Linear RGB of an EXR file's bytes.
fn exr_pixels(bytes: &[u8]) -> Vec<f32> {
    image::load_from_memory(bytes).unwrap().into_rgb32f().into_raw()
}

fn assert_same_image(a: &[f32], b: &[f32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: sizes");
    let mean = b.iter().map(|&x| x as f64).sum::<f64>() / b.len() as f64;
    assert!(mean > 0.01, "{what}: a black image");
    // The same samples summed in another order: equal to float rounding.
    let worst = a.iter().zip(b).map(|(x, y)| ((x - y).abs() / (1e-3 + y.abs())) as f64).fold(0.0, f64::max);
    assert!(worst < 1e-3, "{what}: pixels differ by up to {worst} relative");
}

const SMALL: &[&str] = &["-r", "64", "48", "-s", "64", "-m", "3", "-t", "2"];

/// Mean squared error of `a` against `b`, values clamped to [0, 1] (as displayed: a rare
/// bright sample counts as a white pixel, not as its radiance).
fn displayed_mse(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    let c = |x: f32| x.clamp(0.0, 1.0) as f64;
    a.iter().zip(b).map(|(&x, &y)| (c(x) - c(y)).powi(2)).sum::<f64>() / a.len() as f64
}

/// The converged frame is the offline render (the same sample indices, summed in batches);
/// after a camera move the coarse frame comes first, then the image refines to the cap; the
/// command and camera file it gives render that same view offline.
#[test]
fn view_converges_to_the_offline_render_and_its_command_reproduces_the_view() {
    let dir = temp_dir("view-offline");
    let view = View::start(SMALL);
    let (s, page) = view.get("/");
    assert!(s == 200 && String::from_utf8_lossy(&page).contains("<canvas id=\"image\""));
    let first = view.wait(1, |v| v["converged"] == true);
    assert_eq!(first["spp"], 64);
    let (s, exr) = view.get("/image.exr");
    assert_eq!(s, 200);
    let out = dir.join("offline.exr");
    let r = Command::new(wavepath_bin()).args(SMALL).args(["-f", out.to_str().unwrap()]).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_same_image(&exr_pixels(&exr), &exr_pixels(&std::fs::read(&out).unwrap()), "converged view vs offline");

    // A move: a new generation whose first frame is the quarter-resolution one-sample image
    // (seen on the frame stream, opened before the move).
    let mut events = view.events();
    let g = generation(&view.post("/control?orbit=0.6,0.15&zoom=0.8&spp=16").1);
    let coarse = loop {
        let f = next_frame(&mut events);
        if f["generation"].as_u64().unwrap() >= g {
            break f;
        }
    };
    assert_eq!((coarse["width"].as_u64(), coarse["spp"].as_u64()), (Some(16), Some(0)), "{}", coarse["info"]);
    view.wait(g, |v| v["converged"] == true && v["spp"] == 16);
    let (_, moved) = view.get("/image.exr");
    let moved = exr_pixels(&moved);
    let (s, cmd) = view.get("/command");
    assert_eq!(s, 200);
    let cmd: serde_json::Value = serde_json::from_slice(&cmd).unwrap();
    std::fs::write(dir.join(cmd["camera_file_name"].as_str().unwrap()), cmd["camera_file"].as_str().unwrap()).unwrap();
    let words: Vec<String> = cmd["command"].as_str().unwrap().split_whitespace().skip(1).map(String::from).collect();
    let words: Vec<String> = words
        .into_iter()
        .map(|w| if w == "view.png" { "view.exr".into() } else { w })
        .chain(["-t".into(), "2".into()])
        .collect();
    let r = Command::new(wavepath_bin()).current_dir(&dir).args(&words).output().unwrap();
    assert!(r.status.success(), "{words:?}: {}", String::from_utf8_lossy(&r.stderr));
    assert_same_image(
        &moved,
        &exr_pixels(&std::fs::read(dir.join("view.exr")).unwrap()),
        "view after a move vs its command",
    );
    assert!(view.interrupt().contains("stopped"));
}

/// A new size is a new plan: the view fits the file's camera to it by the `--fov` rule, as an
/// offline render at that size does, and going back to the first size gives the first image
/// (no fit was written into the view's scene on the way).
#[test]
fn view_refits_the_camera_to_a_new_size_as_an_offline_render_does() {
    let dir = temp_dir("view-resize");
    let args = |w: &str, h: &str| -> Vec<String> {
        ["-r", w, h, "-s", "8", "-m", "2", "-t", "2", "--fov", "frame"].map(String::from).to_vec()
    };
    let offline = |w: &str, h: &str| {
        let out = dir.join(format!("offline-{w}x{h}.exr"));
        let r = Command::new(wavepath_bin()).args(args(w, h)).args(["-f", out.to_str().unwrap()]).output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        exr_pixels(&std::fs::read(&out).unwrap())
    };
    let view = View::start(&args("64", "48").iter().map(String::as_str).collect::<Vec<_>>());
    view.wait(1, |v| v["converged"] == true);
    let (_, first) = view.get("/image.exr");
    let first = exr_pixels(&first);
    assert_same_image(&first, &offline("64", "48"), "first size vs offline");
    let g = generation(&view.post("/control?res=36x40").1);
    view.wait(g, |v| v["converged"] == true && v["width"] == 36);
    let (_, resized) = view.get("/image.exr");
    assert_same_image(&exr_pixels(&resized), &offline("36", "40"), "new size vs offline");
    let g = generation(&view.post("/control?res=64x48").1);
    view.wait(g, |v| v["converged"] == true && v["width"] == 64);
    let (_, back) = view.get("/image.exr");
    assert_same_image(&exr_pixels(&back), &first, "first size again");
    assert!(view.interrupt().contains("stopped"));
}

/// Bad requests get a status and a message; nothing a client sends reaches the file system;
/// several frame streams can watch one render; Ctrl-C stops it cleanly.
#[test]
fn view_refuses_bad_requests_and_serves_several_clients() {
    let dir = temp_dir("view-bad");
    let view = View::start(&[SMALL, &["--save-dir", dir.to_str().unwrap()]].concat());
    view.wait(1, |_| true);
    for (method, path, status) in [
        ("POST", "/control?spp=abc", 400),
        ("POST", "/control?spp=0", 400),
        ("POST", "/control?res=100000x2", 400),
        ("POST", "/control?orbit=NaN,1", 400),
        ("POST", "/control?nonsense=1", 400),
        ("POST", "/control", 400),
        ("GET", "/control?spp=4", 405),
        ("GET", "/../../etc/passwd", 404),
        ("GET", "/view.rs", 404),
        ("POST", "/save?format=../../x", 400),
        ("POST", "/save?path=/etc/passwd", 400),
    ] {
        let (s, head, body) = view.request(method, path);
        assert_eq!(s, status, "{method} {path}: {head} {}", String::from_utf8_lossy(&body));
        assert!(!body.is_empty(), "{method} {path}: no message");
    }
    let (s, name) = view.post("/save?format=png");
    assert_eq!(s, 200, "{name}");
    assert!(dir.join(name.trim()).is_file() && std::fs::read_dir(&dir).unwrap().count() == 1);
    // Streams that stop reading after their status line (slow clients) up to the limit,
    // then one more: refused with a 503; the render still converges (frames are dropped for
    // them, never queued) and Ctrl-C still ends the process.
    let status = |s: &mut BufReader<TcpStream>| {
        let mut line = String::new();
        s.read_line(&mut line).unwrap();
        line
    };
    let mut idle = Vec::new();
    for _ in 0..wavepath_apps::view::server::MAX_STREAMS {
        let mut s = view.events();
        assert!(status(&mut s).contains(" 200 "));
        idle.push(s);
    }
    let mut extra = view.events();
    assert!(status(&mut extra).contains(" 503 "), "stream {} past the limit", idle.len() + 1);
    let g = generation(&view.post("/control?spp=256").1);
    view.wait(g, |v| v["converged"] == true && v["spp"] == 256);
    drop((idle, extra));

    // Two more streams (the idle ones' slots free as their writes fail or time out; the limit
    // is checked above), each gets frames as the render refines.
    // A closed stream's slot frees when the server's next write to it fails (a new frame, or
    // its keep-alive comment within 5 s): retry a refused stream for up to 15 s.
    let open = || {
        let t = Instant::now();
        loop {
            let mut s = view.events();
            if status(&mut s).contains(" 200 ") {
                return s;
            }
            assert!(t.elapsed() < Duration::from_secs(15), "stream slots never freed");
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    let streams: Vec<_> = (0..2).map(|_| open()).collect();
    // A new generation after both are open: each sees its frames.
    let g = generation(&view.post("/control?spp=64&m=2").1);
    for mut s in streams {
        let first = next_frame(&mut s);
        let second = next_frame(&mut s);
        assert!(second["seq"].as_u64() > first["seq"].as_u64());
        assert!(second["generation"].as_u64() >= Some(g));
        assert!(!second["image"].as_str().unwrap().is_empty());
    }
    assert!(view.interrupt().contains("stopped"));
}

/// Each output variable is shown from the same canvas: the first one restarts the render
/// with a canvas that keeps first-hit sums, the others (and the picture again) only show the
/// sums another way, and the next camera move drops them. Each frame has the variable's
/// values (albedo in [0, 1], unit normals, depths, positions, variances) and its display
/// image. An unknown name is refused in one line; without a denoiser the page says how to
/// get one and a request to denoise is refused in one line.
#[test]
fn view_shows_each_output_variable_and_refuses_what_it_cannot_show() {
    // No python3 on the PATH: no pyoidn, so no denoiser whatever this machine has.
    // The whole frame of the Cornell box (red and blue walls, spheres), not its centre.
    let args = [SMALL, &["--fov", "frame"]].concat();
    let view = View::start_with(&args, &[("PATH", "/nonexistent")]);
    let first = view.wait(1, |v| v["converged"] == true);
    assert_eq!((first["show"].as_str(), first["info"]["first_hits"].as_bool()), (Some("picture"), Some(false)));
    let (_, picture) = view.get("/image.exr");
    let picture = exr_pixels(&picture);
    let (_, picture_png) = view.get("/frame");
    let mut current = first["generation"].as_u64().unwrap();
    for name in ["albedo", "normal", "depth", "position", "variance"] {
        let g = generation(&view.post(&format!("/control?show={name}")).1);
        // Only the first variable restarts the render (the canvas then keeps first hits).
        assert_eq!(g, if name == "albedo" { current + 1 } else { current }, "{name}");
        current = g;
        let f = view.wait(g, |v| v["show"] == name && v["converged"] == true);
        assert_eq!(f["info"]["first_hits"], true, "{name}");
        assert!(f["info"]["display"].as_str().is_some_and(|d| !d.is_empty()), "{name}: {}", f["info"]);
        let (s, exr) = view.get("/image.exr");
        assert_eq!(s, 200);
        let values = exr_pixels(&exr);
        assert_eq!(values.len(), picture.len(), "{name}");
        assert!(values.iter().all(|x| x.is_finite()), "{name}: non-finite values");
        let (lo, hi) = values.iter().fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        let mean = values.iter().map(|&x| x as f64).sum::<f64>() / values.len() as f64;
        let off_picture = values.iter().zip(&picture).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / mean.max(1e-9);
        println!("{name}: values in [{lo:.4}, {hi:.4}], mean {mean:.4}; display: {}", f["info"]["display"]);
        assert!(off_picture > 0.05 * values.len() as f64, "{name}: the same as the picture");
        match name {
            "albedo" => assert!(lo >= 0.0 && hi <= 1.0 && mean > 0.05, "albedo outside [0, 1] or black"),
            "normal" => {
                assert!(lo >= -1.0 && hi <= 1.0, "normal components outside [-1, 1]");
                // Means of unit normals (zero where the camera ray escapes): no longer than 1,
                // most of those of surfaces close to it.
                let lengths: Vec<f32> =
                    values.chunks(3).map(|n| (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()).collect();
                let surfaces = lengths.iter().filter(|&&l| l > 0.01).count();
                assert!(lengths.iter().all(|&l| l <= 1.0 + 1e-3) && surfaces > lengths.len() / 4);
                let unit = lengths.iter().filter(|&&l| l > 0.99).count();
                println!("normals: {surfaces} of {} pixels see surfaces, {unit} of them unit normals", lengths.len());
                assert!(unit * 2 > surfaces, "normals not unit");
            }
            "depth" => assert!(lo >= 0.0 && hi > 0.0 && values.chunks(3).all(|d| d[0] == d[1] && d[1] == d[2])),
            "position" => assert!(hi > lo, "one position everywhere"),
            "variance" => assert!(lo >= 0.0 && hi > 0.0, "no variance at 64 spp"),
            _ => unreachable!(),
        }
        // The image shown: the image's size, not the picture's, not flat.
        let (s, png) = view.get("/frame");
        assert_eq!(s, 200);
        assert_ne!(png, picture_png, "{name}: the picture's image");
        let shown = image::load_from_memory(&png).unwrap().into_rgb8();
        assert_eq!(shown.dimensions(), (64, 48));
        let colours: std::collections::BTreeSet<[u8; 3]> = shown.pixels().map(|p| p.0).collect();
        assert!(colours.len() > 10, "{name}: {} colours", colours.len());
    }
    // Back to the picture: no restart, the same converged picture (the sums are kept until
    // the next change restarts the render, which then keeps none).
    let g = generation(&view.post("/control?show=picture").1);
    assert_eq!(g, current);
    view.wait(g, |v| v["show"] == "picture" && v["converged"] == true);
    let (_, again) = view.get("/image.exr");
    assert_same_image(&exr_pixels(&again), &picture, "the picture after the variables");
    let g = generation(&view.post("/control?orbit=0.1,0").1);
    let moved = view.wait(g, |v| v["converged"] == true);
    assert_eq!(moved["info"]["first_hits"], false, "a picture's render keeps first hits");

    // Refused in one line each: an unknown name, and denoising without a denoiser (whose
    // absence the page's figures carry, with how to get one).
    let (s, e) = view.post("/control?show=beauty");
    assert_eq!((s, e.trim()), (400, "show must be picture, albedo, normal, depth, position or variance, got 'beauty'"));
    let (s, e) = view.post("/control?denoise=1");
    assert_eq!(s, 400, "{e}");
    assert!(e.trim().lines().count() == 1 && e.contains("pip install pyoidn"), "{e}");
    assert_eq!(moved["info"]["denoiser"]["available"], false);
    assert!(moved["info"]["denoiser"]["help"].as_str().unwrap().contains("pip install pyoidn"));
    let err = view.interrupt();
    assert!(err.contains("denoising off") && err.contains("pyoidn"), "{err}");

    // A runtime named on the command line must load: else the viewer does not start.
    let r = Command::new(wavepath_bin()).args(["view", "--oidn", "/nonexistent/oidn"]).args(&args).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success() && err.trim().lines().count() == 1 && err.contains("/nonexistent/oidn"), "{err}");
}

/// With Open Image Denoise, the refining picture is denoised now and then and the final one
/// always; at a few samples per pixel the denoised picture is much closer to the converged one
/// than the raw picture of the same samples is.
#[test]
fn view_denoises_the_picture_with_a_runtime() {
    let Some(oidn) = crate::common::oidn_for_tests("the denoising checks") else { return };
    let oidn = oidn.to_str().unwrap();
    let size = ["-r", "128", "96", "-s", "1024", "-m", "3", "-t", "2", "--fov", "frame"];
    let view = View::start(&[&size[..], &["--oidn", oidn, "--denoise"]].concat());
    // Frames of the first view from the stream: refining ones denoised (after the first pass)
    // and the final one, each with the denoiser's time in its figures.
    let mut events = view.events();
    let mut refining = 0;
    let last = loop {
        let f = next_frame(&mut events);
        if f["denoised"] == true {
            assert!(f["info"]["denoise_s"].as_f64().unwrap() > 0.0, "{}", f["info"]);
            if f["converged"] == true {
                break f;
            }
            refining += 1;
        }
    };
    println!("{refining} denoised refining frames, the final one in {} s", last["info"]["denoise_s"]);
    // A render that refines for a second has frames well after its first pass (at least
    // one goes out every REFINE_GAP), and the denoiser is free for the first of them.
    let render_s = last["info"]["render_s"].as_f64().unwrap();
    assert!(refining >= 1 || render_s < 1.0, "no refining frame was denoised in {render_s} s");
    // The converged raw picture (denoise off: the same sums shown as they are, no restart).
    let g = generation(&view.post("/control?denoise=0").1);
    assert_eq!(g, last["generation"].as_u64().unwrap());
    view.wait(g, |v| v["converged"] == true && v["denoised"] == false);
    let (_, reference) = view.get("/image.exr");
    let reference = exr_pixels(&reference);
    // Eight samples per pixel, denoised and raw.
    let g = generation(&view.post("/control?spp=8&denoise=1").1);
    let denoised_frame = view.wait(g, |v| v["converged"] == true && v["denoised"] == true && v["spp"] == 8);
    let (_, denoised) = view.get("/image.exr");
    view.post("/control?denoise=0");
    view.wait(g, |v| v["converged"] == true && v["denoised"] == false && v["spp"] == 8);
    let (_, raw) = view.get("/image.exr");
    let (denoised, raw) = (exr_pixels(&denoised), exr_pixels(&raw));
    let (e_raw, e_denoised) = (displayed_mse(&raw, &reference), displayed_mse(&denoised, &reference));
    println!(
        "8 spp against 1024 spp: MSE raw {e_raw:.5}, denoised {e_denoised:.5} ({:.1}x lower; denoised in {} s)",
        e_raw / e_denoised,
        denoised_frame["info"]["denoise_s"]
    );
    assert!(e_denoised * 3.0 < e_raw, "denoised MSE {e_denoised} against raw {e_raw}");
    assert!(view.interrupt().contains("denoiser:"));
}

/// The page in a real browser (headless Chromium, Debian's `chromium`): frames arrive, an
/// orbit drag and a wheel zoom each change the image, it converges, and the screenshot is
/// not blank. The screenshot is kept in the test's temporary folder.
#[test]
fn page_in_a_real_browser_orbits_zooms_and_converges() {
    let chromium = ["chromium", "chromium-browser"]
        .into_iter()
        .find(|c| Command::new(c).arg("--version").output().is_ok_and(|o| o.status.success()))
        .expect("Chromium is needed for the browser test (Debian's `chromium`; .ci/run installs it)");
    let dir = temp_dir("view-browser");
    let oidn = crate::common::oidn_for_tests("the denoising checks");
    let mut args = vec!["-r", "160", "120", "-s", "32", "-m", "3", "-t", "2", "--fov", "frame"];
    if let Some(p) = &oidn {
        args.extend(["--oidn", p.to_str().unwrap()]);
    }
    let view = View::start(&args);
    let browser = crate::common::cdp::Browser::launch(chromium, &dir);
    let mut page = browser.open(&format!("http://{}/", view.addr));
    let state = |page: &mut crate::common::cdp::Page| {
        // 'null' until the page has loaded.
        page.eval(
            "typeof viewer === 'undefined' ? 'null' : \
             JSON.stringify({f: viewer.frames, s: viewer.seq, c: viewer.converged, m: viewer.mean(), e: viewer.errors, rs: events.readyState, t: document.getElementById('error').textContent, \
             sh: viewer.show, dn: viewer.denoised, fig: document.getElementById('figures').textContent, \
             box: document.getElementById('denoise').disabled, note: document.getElementById('denoise-note').textContent, \
             sel: document.getElementById('show').value})",
        )
    };
    let wait = |page: &mut crate::common::cdp::Page, what: &str, ok: &dyn Fn(&serde_json::Value) -> bool| {
        let t = Instant::now();
        loop {
            let v: serde_json::Value = serde_json::from_str(state(page).as_str().unwrap()).unwrap();
            if !v.is_null() && ok(&v) {
                return v;
            }
            assert!(t.elapsed() < Duration::from_secs(60), "{what}: {v}");
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    let start = wait(&mut page, "a converged first image", &|v| v["c"] == true);
    // Orbit: a left drag across a quarter of the canvas.
    page.drag((80.0, 60.0), (120.0, 70.0));
    let orbited =
        wait(&mut page, "an image after the orbit drag", &|v| v["s"].as_u64() > start["s"].as_u64() && v["c"] == true);
    assert!((orbited["m"].as_f64().unwrap() - start["m"].as_f64().unwrap()).abs() > 0.2, "{start} -> {orbited}");
    page.wheel((80.0, 60.0), -600.0);
    let zoomed = wait(&mut page, "an image after the wheel zoom", &|v| {
        v["s"].as_u64() > orbited["s"].as_u64() && v["c"] == true
    });
    assert!((zoomed["m"].as_f64().unwrap() - orbited["m"].as_f64().unwrap()).abs() > 0.2, "{orbited} -> {zoomed}");
    assert_eq!(zoomed["e"], 0, "the page reported errors");
    let png = page.screenshot();
    std::fs::write(dir.join("view.png"), &png).unwrap();
    let shot = image::load_from_memory(&png).unwrap().into_rgb8();
    let distinct: std::collections::BTreeSet<[u8; 3]> = shot.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 50, "the screenshot has {} colours: blank", distinct.len());
    assert!(Path::new(&dir.join("view.png")).is_file());

    // An output variable picked in the page's select: its image, named in the figures.
    page.eval("(() => { const s = document.getElementById('show'); s.value = 'normal'; s.dispatchEvent(new Event('change')); })()");
    let normal = wait(&mut page, "the normals", &|v| v["sh"] == "normal" && v["c"] == true);
    assert!(normal["fig"].as_str().unwrap().contains("normal") && normal["sel"] == "normal", "{normal}");
    assert!((normal["m"].as_f64().unwrap() - zoomed["m"].as_f64().unwrap()).abs() > 1.0, "{zoomed} -> {normal}");
    std::fs::write(dir.join("view-normal.png"), page.screenshot()).unwrap();
    // The denoiser: with a runtime, ticking the box on the picture shows it denoised (the
    // figures give its time); without, the box is disabled and the page says how to get one.
    page.eval("(() => { const s = document.getElementById('show'); s.value = 'picture'; s.dispatchEvent(new Event('change')); })()");
    wait(&mut page, "the picture again", &|v| v["sh"] == "picture" && v["c"] == true);
    if oidn.is_some() {
        page.eval("document.getElementById('denoise').click()");
        let denoised = wait(&mut page, "the denoised picture", &|v| v["dn"] == true && v["c"] == true);
        assert!(denoised["fig"].as_str().unwrap().contains("denoised in"), "{denoised}");
        std::fs::write(dir.join("view-denoised.png"), page.screenshot()).unwrap();
    } else {
        let v = wait(&mut page, "the disabled denoise box", &|v| v["box"] == true);
        assert!(v["note"].as_str().unwrap().contains("pip install pyoidn"), "{v}");
        std::fs::write(dir.join("view-no-denoiser.png"), page.screenshot()).unwrap();
    }
    assert_eq!(wait(&mut page, "no errors", &|_| true)["e"], 0, "the page reported errors");
    println!("screenshots in {}", dir.display());
    drop(page);
    drop(browser);
    view.interrupt();
}
