//! `wavepath view` driven as a user drives it: the binary serves on a free port; these tests
//! speak HTTP to it (plain sockets), change the camera and settings, read frames, compare the
//! converged image with the offline render of the same samples, run the command it gives,
//! send it bad input, and stop it with Ctrl-C. The browser test opens the page in headless
//! Chromium and drives it through the DevTools protocol.

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
        let mut child = Command::new(wavepath_bin())
            .arg("view")
            .args(args)
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
    let view = View::start(&["-r", "160", "120", "-s", "32", "-m", "3", "-t", "2"]);
    let browser = crate::common::cdp::Browser::launch(chromium, &dir);
    let mut page = browser.open(&format!("http://{}/", view.addr));
    let state = |page: &mut crate::common::cdp::Page| {
        // 'null' until the page has loaded.
        page.eval(
            "typeof viewer === 'undefined' ? 'null' : \
             JSON.stringify({f: viewer.frames, s: viewer.seq, c: viewer.converged, m: viewer.mean(), e: viewer.errors, rs: events.readyState, t: document.getElementById('error').textContent})",
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
    drop(page);
    drop(browser);
    view.interrupt();
}
