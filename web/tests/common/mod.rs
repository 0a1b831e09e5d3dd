//! What the browser tests share: Chromium found and started, a server for the built page
//! that takes what the page posts, the page built.

#![allow(dead_code)] // each test binary uses its part

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::Sender;
use std::time::{Duration, Instant};

/// Chromium's flags for WebGPU on SwiftShader (which needs Chromium's own Vulkan on
/// SwiftShader, else the canvas's swap chain has no backing and the device is lost) and
/// WebGL2 on ANGLE over SwiftShader.
pub const GPU_FLAGS: &[&str] = &[
    "--enable-unsafe-webgpu",
    "--use-webgpu-adapter=swiftshader",
    "--enable-features=Vulkan",
    "--use-vulkan=swiftshader",
    "--use-angle=swiftshader",
];

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn out_dir(name: &str) -> PathBuf {
    let dir = root().join("target/test-output").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Skips loudly, or fails under `CI`.
pub fn skip(why: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("CI is set but {why}");
    }
    eprintln!("\n!!!! SKIPPING BROWSER TEST: {why} !!!!\n");
}

/// Chromium's binary: `$CHROMIUM`, else `chromium` or `chromium-browser` on the PATH.
pub fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CHROMIUM") {
        return Some(p.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| [d.join("chromium"), d.join("chromium-browser")])
        .find(|p| p.is_file())
}

/// What the page posted.
#[derive(Debug)]
pub struct Post {
    pub path: String,
    pub body: Vec<u8>,
}

/// Serves `dir` (GET) and passes every POST to `posts`, on 127.0.0.1; returns the port.
pub fn serve(dir: PathBuf, posts: Sender<Post>) -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let (dir, posts) = (dir.clone(), posts.clone());
            std::thread::spawn(move || {
                if let Err(e) = answer(stream, &dir, &posts) {
                    eprintln!("test server: {e}");
                }
            });
        }
    });
    port
}

/// One HTTP/1.1 request and its answer (the connection closed after it).
fn answer(stream: TcpStream, dir: &Path, posts: &Sender<Post>) -> std::io::Result<()> {
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    let mut parts = line.split_whitespace();
    let (method, target) = (
        parts.next().unwrap_or("").to_owned(),
        parts.next().unwrap_or("/").to_owned(),
    );
    let mut length = 0usize;
    loop {
        let mut header = String::new();
        if reader.read_line(&mut header)? == 0 || header.trim().is_empty() {
            break;
        }
        if let Some((name, value)) = header.split_once(':')
            && name.eq_ignore_ascii_case("content-length")
        {
            length = value.trim().parse().unwrap_or(0);
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body)?;
    let (status, kind, content) = match method.as_str() {
        "POST" => {
            let _ = posts.send(Post { path: target, body });
            ("200 OK", "text/plain", Vec::new())
        }
        "GET" => {
            let path = target.split('?').next().unwrap_or("/");
            let name = match path.trim_start_matches('/') {
                "" => "index.html",
                n => n,
            };
            let kind = match name.rsplit('.').next() {
                Some("html") => "text/html",
                Some("js") => "text/javascript",
                Some("wasm") => "application/wasm",
                _ => "application/octet-stream",
            };
            // Only the files of the folder itself.
            match (!name.contains(['/', '\\']) && !name.starts_with('.'))
                .then(|| std::fs::read(dir.join(name)).ok())
                .flatten()
            {
                Some(bytes) => ("200 OK", kind, bytes),
                None => ("404 Not Found", "text/plain", b"not found".to_vec()),
            }
        }
        _ => ("405 Method Not Allowed", "text/plain", Vec::new()),
    };
    let mut stream = stream;
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        content.len()
    )?;
    stream.write_all(&content)?;
    stream.flush()
}

/// Headless Chromium on `url`, in a fresh profile (stopped on drop). WebGPU on SwiftShader
/// needs Chromium's Vulkan on SwiftShader too (else the canvas's swap chain has no
/// shared-image backing and the device is lost); WebGL2 is ANGLE on SwiftShader. Without
/// the background-networking flags Chromium keeps calling out.
pub struct Browser(Child);

impl Browser {
    pub fn open(binary: &Path, url: &str, profile: &Path) -> Self {
        Self::open_with(binary, url, profile, GPU_FLAGS, None)
    }

    /// Chromium with `gpu` flags (of which [`GPU_FLAGS`] draws on both APIs) and a
    /// window of `size` pixels (Chromium's default when `None`).
    pub fn open_with(
        binary: &Path,
        url: &str,
        profile: &Path,
        gpu: &[&str],
        size: Option<(u32, u32)>,
    ) -> Self {
        let _ = std::fs::remove_dir_all(profile);
        let child = Command::new(binary)
            .args(["--headless=new", "--no-sandbox"])
            .args(gpu)
            .args(size.map(|(w, h)| format!("--window-size={w},{h}")))
            .args([
                "--disable-quic",
                "--no-first-run",
                "--no-default-browser-check",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-default-apps",
                "--disable-extensions",
                "--enable-logging=stderr",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(url)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::from(
                std::fs::File::create(profile.with_extension("log")).unwrap(),
            ))
            .spawn()
            .unwrap();
        Browser(child)
    }
}

impl Drop for Browser {
    /// SIGTERM to the browser process alone (its GPU, renderer and utility processes end
    /// with it), SIGKILL if it has not ended within 10 s.
    fn drop(&mut self) {
        let pid = self.0.id();
        if pid > 1 {
            let _ = Command::new("kill")
                .args(["-s", "TERM", "--", &pid.to_string()])
                .status();
        }
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if matches!(self.0.try_wait(), Ok(Some(_))) {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Builds a page with `bash scripts/web.sh build` into `out` (`WEB_OUT`), from the crate
/// folder `krate` (`WEB_CRATE`; the crate's own page when `None`), with `env` besides.
pub fn build_page(krate: Option<&Path>, out: &Path, env: &[(&str, &str)]) {
    let mut build = Command::new("bash");
    build
        .arg(root().join("scripts/web.sh"))
        .arg("build")
        .current_dir(root())
        .env("WEB_OUT", out)
        .envs(env.iter().copied());
    if let Some(k) = krate {
        build.env("WEB_CRATE", k);
    }
    let status = build.status().unwrap();
    assert!(
        status.success(),
        "bash scripts/web.sh build failed ({krate:?})"
    );
}

/// The bytes of a `data:image/png;base64,...` URL.
pub fn png_of_data_url(url: &str) -> Option<Vec<u8>> {
    let b64 = url.trim().strip_prefix("data:image/png;base64,")?;
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let mut out = Vec::with_capacity(b64.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0);
    for c in b64.bytes().take_while(|&c| c != b'=') {
        acc = (acc << 6) | u32::from(value(c)?);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// A report a page posted (`key: value` lines), as its fields; a key that repeats keeps its
/// last value.
#[derive(Debug, Clone)]
pub struct Report(HashMap<String, String>);

impl Report {
    pub fn parse(text: &str) -> Self {
        Self(
            text.lines()
                .filter_map(|l| l.split_once(": "))
                .map(|(k, v)| (k.to_owned(), v.to_owned()))
                .collect(),
        )
    }

    pub fn get(&self, key: &str) -> &str {
        self.0
            .get(key)
            .map_or_else(|| panic!("no {key} in {self:?}"), String::as_str)
    }

    pub fn number(&self, key: &str) -> u64 {
        self.get(key)
            .parse()
            .unwrap_or_else(|_| panic!("{key}: {:?}", self.get(key)))
    }
}
