//! What the `gait review` tests share: a running review server, and the browser scripts of
//! tests/review/ (node and Debian's Chromium).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};

use crate::common::{self, gait};

/// `gait review ...` running on a free port; killed when dropped.
pub struct Server {
    child: Child,
    pub url: String,
}

impl Server {
    pub fn start(args: &[&std::ffi::OsStr]) -> Server {
        let mut child = gait()
            .arg("review")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("gait review starts");
        let mut line = String::new();
        BufReader::new(child.stdout.as_mut().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line.trim().to_string();
        assert!(url.starts_with("http://127.0.0.1:"), "printed {url:?}");
        Server { child, url }
    }

    pub fn token(&self) -> &str {
        self.url.split("token=").nth(1).unwrap()
    }

    pub fn addr(&self) -> &str {
        self.url
            .trim_start_matches("http://")
            .split('/')
            .next()
            .unwrap()
    }

    /// A plain HTTP/1.1 request; returns the status and the body.
    pub fn request(&self, method: &str, target: &str, body: &str) -> (u16, String) {
        let mut s = TcpStream::connect(self.addr()).unwrap();
        write!(
            s,
            "{method} {target} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
            self.addr(),
            body.len()
        )
        .unwrap();
        let mut reply = Vec::new();
        s.read_to_end(&mut reply).unwrap();
        let reply = String::from_utf8_lossy(&reply).to_string();
        let status = reply.split(' ').nth(1).unwrap().parse().unwrap();
        let body = reply.split("\r\n\r\n").nth(1).unwrap_or("").to_string();
        (status, body)
    }

    pub fn get(&self, path: &str) -> (u16, String) {
        let sep = if path.contains('?') { '&' } else { '?' };
        self.request("GET", &format!("{path}{sep}token={}", self.token()), "")
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn node_modules() -> String {
    common::tool_output("tools/review/setup_puppeteer.sh", &[])
}

/// Runs `tests/review/SCRIPT` in node with `args`: it drives Debian's Chromium over the
/// DevTools protocol and must succeed.
pub fn in_browser(script: &str, args: &[&std::ffi::OsStr]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/review")
        .join(script);
    let mut node = Command::new("node");
    node.arg(path).args(args).env("NODE_PATH", node_modules());
    if let Some(b) = gait_report::pdf::find_chromium() {
        node.env("CHROMIUM", b);
    }
    let out = node.output().expect("node runs");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
