//! Live preview in the [tev](https://github.com/Tom94/tev) viewer: `photon render
//! --display-server HOST:PORT` (pbrt-v4's flag) sends the image to a tev listening there as the
//! render goes: each tile as it finishes, or the whole image each time a pass is added.
//!
//! tev's protocol (its `Ipc.h`), all little-endian, every packet `u32 length` (the whole packet,
//! these four bytes included), `u8 type`, then:
//! - `CreateImage` (type 4): `u8 grab_focus`, name (NUL-terminated UTF-8), `i32 width`,
//!   `i32 height`, `i32 channels`, the channel names (NUL-terminated each);
//! - `UpdateImage` v3 (type 6): `u8 grab_focus`, name, `i32 channels`, the channel names,
//!   `i32 x, y, width, height`, `i64` offset of each channel, `i64` stride of each channel (in
//!   floats), then the `f32` pixels (here interleaved: offset `c`, stride = channels).
//!
//! The channels are `R, G, B` (the beauty) and `direct.R`, ... per component layer, as in the
//! EXR. The render never waits for the viewer: observers copy pixels into a frame under a mutex
//! and a sender thread ships what changed. Without a viewer at the address the render goes on
//! with a one-line warning; if the viewer goes away during the render, the sender reconnects once
//! (trying at most once a second) and sends the whole frame again.
use crate::film::{Component, Radiance};
use crate::imageio::RgbImage;
use crate::integrator::Observer;
use std::io::Write;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// tev's packet types.
const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;

/// How long a connection attempt or one packet's write may take before the viewer is
/// considered gone.
const TIMEOUT: Duration = Duration::from_secs(2);

/// Parses `HOST:PORT` (as `--display-server` takes it) to a socket address.
pub fn parse_server(s: &str) -> Result<String, String> {
    match s.rsplit_once(':') {
        Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok() => Ok(s.to_string()),
        _ => Err(format!(
            "expected HOST:PORT (e.g. localhost:14158), got {}",
            crate::scene::clip_for_message(s, 60)
        )),
    }
}

/// The channel names of a frame: beauty, then each component layer.
pub fn channel_names() -> Vec<String> {
    let mut names: Vec<String> = ["R", "G", "B"].map(String::from).to_vec();
    for layer in Component::NAMES {
        names.extend(["R", "G", "B"].map(|c| format!("{layer}.{c}")));
    }
    names
}

/// Channels per pixel of a frame: beauty and the four component layers, RGB each.
const CHANNELS: usize = 3 * (1 + Component::NAMES.len());

/// A `CreateImage` packet.
pub fn create_image(name: &str, width: u32, height: u32, channels: &[String]) -> Vec<u8> {
    packet(CREATE_IMAGE, |b| {
        b.push(1); // grab focus
        put_str(b, name);
        for v in [width as i32, height as i32, channels.len() as i32] {
            b.extend(v.to_le_bytes());
        }
        channels.iter().for_each(|c| put_str(b, c));
    })
}

/// An `UpdateImage` (v3) packet for the rectangle `[x, x + width) x [y, y + height)`: `data`
/// holds `channels.len()` interleaved floats per pixel, row-major.
pub fn update_image(
    name: &str,
    channels: &[String],
    [x, y, width, height]: [u32; 4],
    data: &[f32],
) -> Vec<u8> {
    let n = channels.len();
    debug_assert_eq!(data.len(), n * (width * height) as usize);
    packet(UPDATE_IMAGE_V3, |b| {
        b.push(0); // do not grab focus on every tile
        put_str(b, name);
        b.extend((n as i32).to_le_bytes());
        channels.iter().for_each(|c| put_str(b, c));
        for v in [x, y, width, height] {
            b.extend((v as i32).to_le_bytes());
        }
        (0..n).for_each(|c| b.extend((c as i64).to_le_bytes()));
        (0..n).for_each(|_| b.extend((n as i64).to_le_bytes()));
        b.reserve(data.len() * 4);
        data.iter().for_each(|v| b.extend(v.to_le_bytes()));
    })
}

fn packet(kind: u8, body: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut b = vec![0, 0, 0, 0, kind];
    body(&mut b);
    let n = b.len() as u32;
    b[..4].copy_from_slice(&n.to_le_bytes());
    b
}

/// A NUL-terminated string (NULs inside are dropped: tev would cut the name there).
fn put_str(b: &mut Vec<u8>, s: &str) {
    b.extend(s.bytes().filter(|&c| c != 0));
    b.push(0);
}

/// What the observers and the sender thread share.
struct Frame {
    width: u32,
    height: u32,
    /// [`CHANNELS`] floats per pixel.
    pixels: Vec<f32>,
    /// Rectangles `[x, y, w, h]` changed since the sender last looked.
    dirty: Vec<[u32; 4]>,
    /// The render is over: send what is dirty and stop.
    done: bool,
    /// The sender has given up (no viewer, or gone twice): observers skip their copies.
    gone: bool,
}

struct Shared {
    frame: Mutex<Frame>,
    wake: Condvar,
}

impl Shared {
    fn lock(&self) -> std::sync::MutexGuard<'_, Frame> {
        self.frame.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// A live preview: an [`Observer`] of a render that feeds a tev viewer.
pub struct Display {
    shared: Arc<Shared>,
    sender: Option<JoinHandle<()>>,
}

impl Display {
    /// Starts the preview of a `width x height` image named `name` at `server` (`HOST:PORT`).
    /// Connecting happens on the sender thread: this never blocks.
    pub fn start(server: &str, name: &str, width: u32, height: u32) -> Display {
        let n = (width as usize) * (height as usize) * CHANNELS;
        let shared = Arc::new(Shared {
            frame: Mutex::new(Frame {
                width,
                height,
                pixels: vec![0.0; n],
                dirty: Vec::new(),
                done: false,
                gone: false,
            }),
            wake: Condvar::new(),
        });
        let (s, server, name) = (Arc::clone(&shared), server.to_string(), name.to_string());
        let sender = std::thread::Builder::new()
            .name("tev".into())
            .spawn(move || send_loop(&s, &server, &name))
            .ok();
        if sender.is_none() {
            say_err!("photon: warning: --display-server: cannot start its thread: no preview");
            shared.lock().gone = true;
        }
        Display { shared, sender }
    }

    /// Sends what is left and waits for the sender (at most [`TIMEOUT`] per packet when the
    /// viewer stalls).
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        self.shared.lock().done = true;
        self.shared.wake.notify_all();
        if let Some(t) = self.sender.take() {
            let _ = t.join();
        }
    }

    /// Whether a viewer may still see the image (false once the sender has given up): callers
    /// can skip preparing what they would show.
    pub fn watching(&self) -> bool {
        !self.shared.lock().gone
    }

    /// Marks `rect` changed and wakes the sender.
    fn changed(&self, mut f: std::sync::MutexGuard<'_, Frame>, rect: [u32; 4]) {
        f.dirty.push(rect);
        drop(f);
        self.shared.wake.notify_one();
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        self.stop();
    }
}

impl Observer for Display {
    fn tile_pixels(&self, x0: u32, y0: u32, x1: u32, y1: u32, px: &[Radiance]) {
        let mut f = self.shared.lock();
        if f.gone {
            return;
        }
        let w = f.width as usize;
        let tw = (x1 - x0) as usize;
        for (i, r) in px.iter().enumerate() {
            let (x, y) = (x0 as usize + i % tw, y0 as usize + i / tw);
            let k = (y * w + x) * CHANNELS;
            let Some(dst) = f.pixels.get_mut(k..k + CHANNELS) else {
                continue;
            };
            dst[..3].copy_from_slice(&r.total().to_array());
            for (c, v) in r.0.iter().enumerate() {
                dst[3 + 3 * c..6 + 3 * c].copy_from_slice(&v.to_array());
            }
        }
        self.changed(f, [x0, y0, x1 - x0, y1 - y0]);
    }

    fn image(&self, image: &RgbImage, layers: &[(&'static str, RgbImage)], _pass: u64) {
        let mut f = self.shared.lock();
        if f.gone || (image.width, image.height) != (f.width as usize, f.height as usize) {
            return;
        }
        for (i, dst) in f.pixels.chunks_exact_mut(CHANNELS).enumerate() {
            dst[..3].copy_from_slice(&image.pixels[i]);
            for (c, (_, l)) in layers.iter().take(Component::NAMES.len()).enumerate() {
                dst[3 + 3 * c..6 + 3 * c].copy_from_slice(&l.pixels[i]);
            }
        }
        f.dirty.clear();
        let (w, h) = (f.width, f.height);
        self.changed(f, [0, 0, w, h]);
    }
}

/// The sender thread: connects, creates the image, then sends each changed rectangle (in tiles
/// of at most 128 x 128 pixels, as tev's own client does) until the render is done.
fn send_loop(shared: &Shared, server: &str, name: &str) {
    send_frames(shared, server, name);
    let mut f = shared.lock();
    (f.gone, f.dirty) = (true, Vec::new());
}

/// [`send_loop`]'s work, until the render is done or the viewer is given up.
fn send_frames(shared: &Shared, server: &str, name: &str) {
    let channels = channel_names();
    let (width, height) = {
        let f = shared.lock();
        (f.width, f.height)
    };
    let create = create_image(name, width, height, &channels);
    let mut conn = match connect(server).and_then(|mut s| s.write_all(&create).map(|()| s)) {
        Ok(s) => Some(s),
        Err(e) => {
            say_err!(
                "photon: warning: --display-server {server}: no viewer ({e}): rendering without preview"
            );
            return;
        }
    };
    // After a lost connection: whether the one reconnection is still allowed, and when it
    // was last tried.
    let (mut may_reconnect, mut last_try) = (true, None::<Instant>);
    loop {
        let (mut pieces, done) = {
            let mut f = shared.lock();
            while f.dirty.is_empty() && !f.done {
                f = shared.wake.wait(f).unwrap_or_else(|e| e.into_inner());
            }
            let dirty = std::mem::take(&mut f.dirty);
            (
                dirty.into_iter().flat_map(split).collect::<Vec<_>>(),
                f.done,
            )
        };
        // Send; when the viewer is found gone, reconnect at once if that is still allowed.
        loop {
            let due = last_try.is_none_or(|t| t.elapsed().as_secs() >= 1);
            if conn.is_none() && may_reconnect && due {
                last_try = Some(Instant::now());
                if let Ok(mut s) = connect(server) {
                    may_reconnect = false;
                    if s.write_all(&create).is_ok() {
                        conn = Some(s);
                        // The whole frame: the viewer lost everything.
                        pieces = split([0, 0, width, height]);
                    }
                }
            }
            let Some(s) = conn.as_mut() else { break };
            if send(s, shared, name, &channels, &pieces).is_ok() {
                break;
            }
            conn = None;
            if !may_reconnect {
                say_err!(
                    "photon: warning: --display-server {server}: viewer gone again: preview stopped"
                );
                break;
            }
        }
        if done || (conn.is_none() && !may_reconnect) {
            return;
        }
    }
}

/// Sends `pieces` of the frame, one at a time: the copy and its packet stay small (a 128 x
/// 128 piece is 1 MB) and the observers wait for the lock only as long as one copy.
fn send(
    s: &mut TcpStream,
    shared: &Shared,
    name: &str,
    channels: &[String],
    pieces: &[[u32; 4]],
) -> std::io::Result<()> {
    for &r in pieces {
        let data = copy_rect(&shared.lock(), r);
        s.write_all(&update_image(name, channels, r, &data))?;
    }
    Ok(())
}

fn connect(server: &str) -> std::io::Result<TcpStream> {
    let addrs: Vec<SocketAddr> = server.to_socket_addrs()?.collect();
    let mut last = std::io::Error::new(std::io::ErrorKind::NotFound, "no address");
    for a in addrs {
        match TcpStream::connect_timeout(&a, TIMEOUT) {
            Ok(s) => {
                s.set_write_timeout(Some(TIMEOUT))?;
                s.set_nodelay(true)?;
                return Ok(s);
            }
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// A rectangle cut into pieces of at most 128 x 128 pixels.
fn split([x, y, w, h]: [u32; 4]) -> Vec<[u32; 4]> {
    const MAX: u32 = 128;
    let mut out = Vec::new();
    for y0 in (y..y + h).step_by(MAX as usize) {
        for x0 in (x..x + w).step_by(MAX as usize) {
            out.push([x0, y0, MAX.min(x + w - x0), MAX.min(y + h - y0)]);
        }
    }
    out
}

/// The pixels of `[x, y, w, h]`, [`CHANNELS`] interleaved floats each.
fn copy_rect(f: &Frame, [x, y, w, h]: [u32; 4]) -> Vec<f32> {
    let mut out = Vec::with_capacity((w * h) as usize * CHANNELS);
    for row in y..y + h {
        let k = ((row * f.width + x) as usize) * CHANNELS;
        out.extend_from_slice(&f.pixels[k..k + w as usize * CHANNELS]);
    }
    out
}
