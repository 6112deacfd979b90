//! The viewer's HTTP side: one embedded page, a server-sent-events stream of frames, and the
//! control, image, save and command endpoints. Nothing a client sends names a file: saves go
//! to the folder given on the command line under names the server makes.

use super::controls::{Change, parse_query, show_name};
use super::options::ViewOptions;
use super::session::{Frame, Look, NO_DENOISER, Session};
use anyhow::{Context, Result};
use base64::Engine;
use std::io::Write;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
use tiny_http::{Header, Method, Request, Response, Server};
use wavepath::Bvh;
use wavepath::Scene;
use wavepath::write_image;

/// The page: HTML and a little JavaScript, no framework, no build step.
const PAGE: &str = include_str!("page.html");

/// Frame streams open at once; more get a 503 (each holds a thread).
pub const MAX_STREAMS: usize = 16;

/// A running viewer: its address and the session it serves.
pub struct Viewer {
    server: Arc<Server>,
    pub addr: SocketAddr,
    pub session: Arc<Session>,
}

impl Viewer {
    /// Binds the address (port 0: a free one).
    pub fn bind(scene: &Scene, settings: wavepath::Settings, opts: &ViewOptions) -> Result<Viewer> {
        let server = Server::http(opts.listen).map_err(|e| anyhow::anyhow!("cannot listen on {}: {e}", opts.listen))?;
        let addr = server.server_addr().to_ip().context("the server has no IP address")?;
        let look = Look { show: opts.show, denoise: opts.denoise };
        let session = Session::new(scene, settings, opts.denoiser.clone(), look);
        Ok(Viewer { server: Arc::new(server), addr, session })
    }

    /// Serves requests and renders until the session is stopped; the render thread is
    /// joined before this returns. The renders run on a pool of `threads` workers (`-t`; 0:
    /// every core) of their own, as the command line's do: the render thread is no worker of
    /// a caller's pool, and would otherwise render on rayon's global one.
    pub fn run(&self, scene: Scene, bvh: &Bvh, opts: &ViewOptions, threads: usize) -> Result<()> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        let streams = Arc::new(AtomicUsize::new(0));
        std::thread::scope(|s| {
            s.spawn(|| pool.install(|| self.session.run(scene, bvh)));
            while !self.session.stopped() {
                let Ok(Some(req)) = self.server.recv_timeout(Duration::from_millis(100)) else { continue };
                let path = req.url().split('?').next().unwrap_or("").to_string();
                if path == "/events" {
                    if streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
                        streams.fetch_sub(1, Ordering::SeqCst);
                        let _ = req.respond(text(503, "too many frame streams open"));
                        continue;
                    }
                    let (session, streams) = (self.session.clone(), streams.clone());
                    // Detached: a client that stops reading blocks its writer, which must
                    // not keep the process alive after Ctrl-C (the render thread is joined).
                    std::thread::spawn(move || {
                        let _ = stream_frames(req.into_writer(), &session);
                        streams.fetch_sub(1, Ordering::SeqCst);
                    });
                    continue;
                }
                let _ = handle(req, &path, &self.session, bvh, opts);
            }
            self.session.stop();
        });
        Ok(())
    }
}

fn header(k: &str, v: &str) -> Header {
    Header::from_bytes(k.as_bytes(), v.as_bytes()).expect("valid header")
}

fn text(code: u16, body: &str) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string(body).with_status_code(code).with_header(header("Content-Type", "text/plain; charset=utf-8"))
}

fn handle(req: Request, path: &str, session: &Session, bvh: &Bvh, opts: &ViewOptions) -> std::io::Result<()> {
    let query = req.url().split_once('?').map(|(_, q)| q.to_string()).unwrap_or_default();
    let post = *req.method() == Method::Post;
    let latest = || session.frame.lock().unwrap().clone();
    match (path, post) {
        ("/", false) => {
            req.respond(Response::from_string(PAGE).with_header(header("Content-Type", "text/html; charset=utf-8")))
        }
        ("/control", true) => match parse_query(&query) {
            Ok(changes) if session.denoiser.is_none() && changes.contains(&Change::Denoise(true)) => {
                req.respond(text(400, NO_DENOISER))
            }
            Ok(changes) => {
                session.apply(&changes, bvh);
                let g = session.state.lock().unwrap().generation;
                req.respond(text(200, &format!("generation {g}")))
            }
            Err(e) => req.respond(text(400, &e)),
        },
        ("/frame", false) => {
            // `after=N`: wait up to 5 s for a frame newer than N.
            let after = query.strip_prefix("after=").and_then(|v| v.parse::<u64>().ok());
            let frame = match after {
                Some(n) => session.frame_after(n, Duration::from_secs(5)),
                None => latest(),
            };
            match frame {
                Some(f) => req.respond(
                    Response::from_data(f.image().to_vec())
                        .with_header(header("Content-Type", f.mime()))
                        .with_header(header("X-Frame", &f.seq.to_string()))
                        .with_header(header("X-Spp", &f.spp.to_string())),
                ),
                None => req.respond(text(404, "no frame yet")),
            }
        }
        ("/info", false) => match latest() {
            Some(f) => req.respond(json_response(&frame_json(&f, false))),
            None => req.respond(text(404, "no frame yet")),
        },
        ("/image.png", false) | ("/image.exr", false) => {
            match latest() {
                Some(f) => {
                    let ext = if path.ends_with("png") { "png" } else { "exr" };
                    match file_bytes(&f, ext) {
                        Ok(bytes) => req.respond(Response::from_data(bytes).with_header(header(
                            "Content-Type",
                            if ext == "png" { "image/png" } else { "image/x-exr" },
                        ))),
                        Err(e) => req.respond(text(500, &format!("{e:#}"))),
                    }
                }
                None => req.respond(text(404, "no frame yet")),
            }
        }
        ("/save", true) => {
            let Some(dir) = &opts.save_dir else {
                return req.respond(text(403, "saving is off: start wavepath view with --save-dir DIR"));
            };
            let ext = match query.as_str() {
                "format=png" => "png",
                "format=exr" => "exr",
                _ => return req.respond(text(400, "save: expected format=png or format=exr")),
            };
            let Some(f) = latest() else { return req.respond(text(404, "no frame yet")) };
            let what = if f.show.is_none() && !f.denoised { String::new() } else { format!("-{}", f.label()) };
            let name = format!("wavepath-view-{:06}-{}spp{what}.{ext}", f.seq, f.spp);
            let written = match (f.show, ext) {
                // A variable's PNG is the image shown (its values mapped for display).
                (Some(_), "png") => {
                    let tmp = dir.join(format!("{name}.tmp"));
                    std::fs::write(&tmp, f.display_png())
                        .and_then(|()| std::fs::rename(&tmp, dir.join(&name)))
                        .map_err(anyhow::Error::from)
                }
                _ => write_image(&f.film, &dir.join(&name), wavepath::Tonemap::Srgb),
            };
            match written {
                Ok(()) => req.respond(text(200, &name)),
                Err(e) => req.respond(text(500, &format!("{e:#}"))),
            }
        }
        ("/command", false) => {
            let st = session.state.lock().unwrap().clone();
            req.respond(json_response(&super::command::reproduce(&st, opts)))
        }
        (_, _)
            if matches!(
                path,
                "/" | "/control" | "/frame" | "/info" | "/image.png" | "/image.exr" | "/save" | "/command"
            ) =>
        {
            req.respond(text(405, "method not allowed"))
        }
        _ => req.respond(text(404, "not found")),
    }
}

fn json_response(v: &serde_json::Value) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string(v.to_string()).with_header(header("Content-Type", "application/json"))
}

/// A frame as the stream sends it: its figures, and (with `image`) the encoded image.
fn frame_json(f: &Frame, image: bool) -> serde_json::Value {
    let mut v = serde_json::json!({
        "seq": f.seq, "generation": f.generation, "width": f.film.width, "height": f.film.height,
        "spp": f.spp, "converged": f.converged, "coarse": f.coarse, "mime": f.mime(), "info": f.info,
        "show": show_name(f.show), "denoised": f.denoised,
    });
    if image {
        v["image"] = base64::engine::general_purpose::STANDARD.encode(f.image()).into();
    }
    v
}

/// The frame's image as a PNG or EXR file's bytes: the picture's PNG sRGB-encoded, a
/// variable's the image shown; an EXR the linear values (the picture, or the variable's).
fn file_bytes(f: &Frame, ext: &str) -> Result<Vec<u8>> {
    if f.show.is_some() && ext == "png" {
        return Ok(f.display_png());
    }
    let dir = std::env::temp_dir().join(format!("wavepath-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("image-{}.{ext}", f.seq));
    write_image(&f.film, &path, wavepath::Tonemap::Srgb)?;
    let bytes = std::fs::read(&path)?;
    let _ = std::fs::remove_file(&path);
    Ok(bytes)
}

/// An `/events` response, written straight to the connection and flushed after every event
/// (a buffering writer would hold an event's end back until the next one): each new frame as
/// one server-sent event, a comment every 5 s without one (so a closed client is noticed),
/// the end when the viewer stops. It always sends the latest frame: a slow client skips
/// frames, it never queues them.
fn stream_frames(mut w: Box<dyn Write + Send>, session: &Session) -> std::io::Result<()> {
    w.write_all(
        b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
    )?;
    w.flush()?;
    let mut last = 0;
    while !session.stopped() {
        match session.frame_after(last, Duration::from_secs(5)) {
            Some(f) => {
                last = f.seq;
                write!(w, "event: frame\ndata: {}\n\n", frame_json(&f, true))?;
            }
            None => w.write_all(b": waiting\n\n")?,
        }
        w.flush()?;
    }
    Ok(())
}
