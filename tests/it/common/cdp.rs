//! A small Chrome DevTools Protocol client for the browser test: launches headless Chromium
//! with remote debugging, opens a page, evaluates JavaScript, sends mouse input and takes
//! screenshots (JSON messages over one WebSocket per page).

use base64::Engine;
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

pub struct Browser {
    child: Child,
    port: u16,
}

impl Browser {
    /// Starts `bin` headless with its profile in `dir`; waits for its DevTools port.
    pub fn launch(bin: &str, dir: &Path) -> Browser {
        let mut child = Command::new(bin)
            .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run"])
            .args(["--remote-debugging-port=0", "--window-size=1000,640", "about:blank"])
            .arg(format!("--user-data-dir={}", dir.join("profile").display()))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("chromium starts");
        let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
        let port = loop {
            let line = lines.next().expect("chromium exited before its DevTools port").unwrap();
            if let Some(rest) = line.split("DevTools listening on ws://127.0.0.1:").nth(1) {
                break rest.split('/').next().unwrap().parse().unwrap();
            }
        };
        // Keep draining stderr so the browser never blocks on a full pipe.
        std::thread::spawn(move || for _ in lines {});
        Browser { child, port }
    }

    /// A new tab showing `url`.
    pub fn open(&self, url: &str) -> Page {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        let port = self.port;
        write!(s, "PUT /json/new?{url} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Length: 0\r\n\r\n").unwrap();
        // The DevTools server keeps the connection open: read the header, then its length.
        let mut r = BufReader::new(s);
        let mut length = 0;
        loop {
            let mut line = String::new();
            r.read_line(&mut line).unwrap();
            if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                length = v.trim().parse().unwrap();
            }
            if line.trim().is_empty() {
                break;
            }
        }
        let mut body = vec![0; length];
        r.read_exact(&mut body).unwrap();
        let target: Value = serde_json::from_slice(&body).unwrap_or_else(|e| panic!("{e}: {body:?}"));
        let ws = target["webSocketDebuggerUrl"].as_str().expect("a debugger URL");
        let (socket, _) = tungstenite::connect(ws).expect("DevTools WebSocket");
        Page { socket, next: 1 }
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub struct Page {
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    next: u64,
}

impl Page {
    /// Calls a DevTools method; its result (events in between are skipped).
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next;
        self.next += 1;
        self.socket.send(Message::text(json!({"id": id, "method": method, "params": params}).to_string())).unwrap();
        loop {
            if let Message::Text(t) = self.socket.read().unwrap() {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["id"] == id {
                    assert!(v.get("error").is_none(), "{method}: {v}");
                    return v["result"].clone();
                }
            }
        }
    }

    /// The value of a JavaScript expression.
    pub fn eval(&mut self, expr: &str) -> Value {
        let r = self.call("Runtime.evaluate", json!({"expression": expr, "returnByValue": true}));
        assert!(r.get("exceptionDetails").is_none(), "{expr}: {r}");
        r["result"]["value"].clone()
    }

    fn mouse(&mut self, kind: &str, (x, y): (f64, f64), extra: Value) {
        let mut p = json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": 1, "clickCount": 1});
        p.as_object_mut().unwrap().extend(extra.as_object().unwrap().clone());
        self.call("Input.dispatchMouseEvent", p);
    }

    /// A left-button drag from `a` to `b` (page coordinates), in eight steps.
    pub fn drag(&mut self, a: (f64, f64), b: (f64, f64)) {
        self.mouse("mousePressed", a, json!({}));
        for k in 1..=8 {
            let f = k as f64 / 8.0;
            self.mouse("mouseMoved", (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)), json!({}));
        }
        self.mouse("mouseReleased", b, json!({"buttons": 0}));
    }

    /// A wheel turn of `dy` at `at`.
    pub fn wheel(&mut self, at: (f64, f64), dy: f64) {
        self.mouse("mouseWheel", at, json!({"button": "none", "buttons": 0, "deltaX": 0, "deltaY": dy}));
    }

    /// A PNG of the page.
    pub fn screenshot(&mut self) -> Vec<u8> {
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}));
        base64::engine::general_purpose::STANDARD.decode(r["data"].as_str().unwrap()).unwrap()
    }
}
