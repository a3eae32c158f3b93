//! `render --display-server` (issue 21): a TCP listener stands in for tev, decodes its IPC
//! protocol with a decoder written here from tev's description (every packet: `u32` length of
//! the whole packet, `u8` type; CreateImage = 4, UpdateImage v3 = 6 with per-channel offsets
//! and strides), assembles the image and compares every channel with the EXR the render wrote,
//! bit for bit. Renders without a viewer, and with a viewer that goes away, still finish and
//! write the same image.
use crate::support::{photon, render_args, small_scene, tmp_dir};
use std::collections::BTreeSet;
use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

/// What a stand-in viewer received on one connection.
#[derive(Default, Debug)]
struct Received {
    /// CreateImage packets: name, width, height, channel names.
    creates: Vec<(String, i32, i32, Vec<String>)>,
    /// Rectangles of the UpdateImage packets, `[x, y, w, h]`, in order.
    updates: Vec<[i32; 4]>,
    /// The image as assembled: per channel name, row-major floats.
    channels: Vec<(String, Vec<f32>)>,
    width: usize,
}

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.0.len() >= n, "packet shorter than its fields");
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn str(&mut self) -> String {
        let end = self
            .0
            .iter()
            .position(|&c| c == 0)
            .expect("NUL-terminated string");
        let s = String::from_utf8(self.0[..end].to_vec()).unwrap();
        self.0 = &self.0[end + 1..];
        s
    }
}

impl Received {
    /// Decodes one packet (without its length field).
    fn packet(&mut self, kind: u8, body: &[u8]) {
        let mut r = Reader(body);
        match kind {
            4 => {
                let _grab = r.u8();
                let name = r.str();
                let (w, h, n) = (r.i32(), r.i32(), r.i32());
                let names: Vec<String> = (0..n).map(|_| r.str()).collect();
                assert!(
                    r.0.is_empty(),
                    "CreateImage has {} bytes too many",
                    r.0.len()
                );
                self.width = w as usize;
                self.channels = names
                    .iter()
                    .map(|c| (c.clone(), vec![f32::NAN; (w * h) as usize]))
                    .collect();
                self.creates.push((name, w, h, names));
            }
            6 => {
                let _grab = r.u8();
                let _name = r.str();
                let n = r.i32() as usize;
                let names: Vec<String> = (0..n).map(|_| r.str()).collect();
                let rect = [r.i32(), r.i32(), r.i32(), r.i32()];
                let offsets: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let data: Vec<f32> =
                    r.0.chunks_exact(4)
                        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                        .collect();
                assert_eq!(r.0.len() % 4, 0);
                let [x, y, w, h] = rect.map(|v| v as usize);
                let pixels = w * h;
                // tev's size check: the largest index any channel reads, plus one.
                let needed = (0..n)
                    .map(|c| offsets[c] + (pixels as i64 - 1) * strides[c] + 1)
                    .max()
                    .unwrap_or(0);
                assert_eq!(data.len() as i64, needed, "UpdateImage data size");
                for (c, name) in names.iter().enumerate() {
                    let (_, dst) = self
                        .channels
                        .iter_mut()
                        .find(|(m, _)| m == name)
                        .unwrap_or_else(|| panic!("update names channel {name} not created"));
                    for i in 0..pixels {
                        let (px, py) = (x + i % w, y + i / w);
                        let v = data[(offsets[c] + i as i64 * strides[c]) as usize];
                        dst[py * self.width + px] = v;
                    }
                }
                self.updates.push(rect);
            }
            k => panic!("unknown packet type {k}"),
        }
    }

    /// Reads packets from `s` until the peer closes it (or `stop_after` updates arrived).
    fn read(&mut self, s: &mut TcpStream, stop_after: Option<usize>) {
        s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
        loop {
            let mut len = [0u8; 4];
            match s.read_exact(&mut len) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return,
                Err(e) => panic!("reading from photon: {e}"),
            }
            let len = u32::from_le_bytes(len) as usize;
            assert!(len >= 5, "packet length {len}");
            let mut body = vec![0u8; len - 4];
            s.read_exact(&mut body).unwrap();
            self.packet(body[0], &body[1..]);
            if stop_after.is_some_and(|n| self.updates.len() >= n) {
                return;
            }
        }
    }
}

/// The EXR's channels as the viewer names them: `R, G, B`, then `layer.R`, ...
fn exr_channels(exr: &Path) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    let beauty = photon::imageio::read_exr(exr).unwrap();
    let mut push = |prefix: &str, img: &photon::imageio::RgbImage| {
        for (c, n) in ["R", "G", "B"].iter().enumerate() {
            let name = format!("{prefix}{n}");
            out.push((name, img.pixels.iter().map(|p| p[c]).collect()));
        }
    };
    push("", &beauty);
    for layer in ["direct", "specular", "caustic", "indirect"] {
        let img = photon::imageio::read_exr_layer(exr, layer).unwrap();
        push(&format!("{layer}."), &img);
    }
    out
}

fn assert_same(got: &Received, exr: &Path) {
    let want = exr_channels(exr);
    let names: Vec<&String> = got.channels.iter().map(|(n, _)| n).collect();
    let want_names: Vec<&String> = want.iter().map(|(n, _)| n).collect();
    assert_eq!(names, want_names, "channels");
    for ((name, a), (_, b)) in got.channels.iter().zip(&want) {
        let differ = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(
            differ,
            0,
            "channel {name}: {differ} of {} pixels differ",
            a.len()
        );
    }
}

fn listener() -> (TcpListener, String) {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = l.local_addr().unwrap().to_string();
    (l, addr)
}

fn scene(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("scene.pbrt");
    let sky = r#"LightSource "infinite" "rgb L" [ 0.2 0.2 0.2 ]"#;
    std::fs::write(&p, small_scene(sky)).unwrap();
    p
}

fn run(args: Vec<std::ffi::OsString>) -> (String, f64) {
    let t = Instant::now();
    let out = photon().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    (stderr, t.elapsed().as_secs_f64())
}

/// Tile by tile: one CreateImage with the 15 channels, one update per 16 x 16 tile (each
/// exactly once), and the assembled image equals the EXR in every channel.
#[test]
fn every_tile_arrives_and_the_image_equals_the_exr() {
    let d = tmp_dir("display_tiles");
    let (l, addr) = listener();
    let viewer = std::thread::spawn(move || {
        let (mut s, _) = l.accept().unwrap();
        let mut got = Received::default();
        got.read(&mut s, None);
        got
    });
    let extra = [
        "--res",
        "40x24",
        "--spp",
        "4",
        "--threads",
        "2",
        "--display-server",
        &addr,
    ];
    let (stderr, _) = run(render_args(&scene(&d), &d, &extra));
    let got = viewer.join().unwrap();
    assert!(!stderr.contains("warning"), "{stderr}");
    assert_eq!(got.creates.len(), 1);
    let (name, w, h, names) = &got.creates[0];
    assert_eq!((name.as_str(), *w, *h), ("out.exr", 40, 24));
    assert_eq!(names.len(), 15);
    // The tile grid: x in 0, 16, 32 (the last 8 wide), y in 0, 16 (the last 8 high).
    let mut want = BTreeSet::new();
    for y in [0, 16] {
        for x in [0, 16, 32] {
            want.insert([
                x,
                y,
                if x == 32 { 8 } else { 16 },
                if y == 16 { 8 } else { 16 },
            ]);
        }
    }
    let tiles: BTreeSet<[i32; 4]> = got.updates.iter().copied().collect();
    assert_eq!(tiles, want, "tiles received: {:?}", got.updates);
    assert_eq!(got.updates.len(), 6, "each tile once: {:?}", got.updates);
    assert_same(&got, &d.join("out.exr"));
}

/// In passes (`--passes 3`): the whole image after each pass, and the last equals the EXR.
#[test]
fn passes_send_the_whole_image_and_the_last_equals_the_exr() {
    let d = tmp_dir("display_passes");
    let (l, addr) = listener();
    let viewer = std::thread::spawn(move || {
        let (mut s, _) = l.accept().unwrap();
        let mut got = Received::default();
        got.read(&mut s, None);
        got
    });
    let extra = [
        "--res",
        "150x140",
        "--spp",
        "2",
        "--passes",
        "3",
        "--display-server",
        &addr,
    ];
    let (stderr, _) = run(render_args(&scene(&d), &d, &extra));
    let got = viewer.join().unwrap();
    assert!(!stderr.contains("warning"), "{stderr}");
    // Each pass is the whole 150 x 140 image in pieces of at most 128 x 128: 4 pieces.
    let pieces = BTreeSet::from([
        [0, 0, 128, 128],
        [128, 0, 22, 128],
        [0, 128, 128, 12],
        [128, 128, 22, 12],
    ]);
    assert!(
        got.updates.len() >= 4 && got.updates.len() % 4 == 0,
        "{:?}",
        got.updates
    );
    for pass in got.updates.chunks(4) {
        assert_eq!(pass.iter().copied().collect::<BTreeSet<_>>(), pieces);
    }
    assert_same(&got, &d.join("out.exr"));
}

/// No viewer at the address: one warning, and the same image as a render without the flag;
/// the times of both are printed (not asserted: tests never fail on timing).
#[test]
fn no_viewer_renders_the_same_image() {
    let d = tmp_dir("display_none");
    let addr = {
        let (l, addr) = listener();
        drop(l);
        addr
    };
    let s = scene(&d);
    let base = ["--res", "64x64", "--spp", "16", "--threads", "2"];
    let (_, t_plain) = run(render_args(&s, &d, &base));
    let plain = std::fs::read(d.join("out.exr")).unwrap();
    let mut extra = base.to_vec();
    extra.extend(["--display-server", &addr]);
    let (stderr, t_none) = run(render_args(&s, &d, &extra));
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("--display-server"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("no viewer"), "{stderr}");
    let a = photon::imageio::read_exr(&d.join("out.exr")).unwrap();
    let b = {
        std::fs::write(d.join("plain.exr"), &plain).unwrap();
        photon::imageio::read_exr(&d.join("plain.exr")).unwrap()
    };
    assert!(a.pixels == b.pixels, "the preview changed the image");
    println!("without --display-server {t_plain:.2} s, with no viewer listening {t_none:.2} s");
}

/// The viewer goes away after the first update and comes back: photon reconnects once,
/// creates the image again and sends it whole, and the second connection ends with the EXR.
#[test]
fn a_restarted_viewer_gets_the_whole_image_again() {
    let d = tmp_dir("display_restart");
    let (l, addr) = listener();
    let viewer = std::thread::spawn(move || {
        let (mut s, _) = l.accept().unwrap();
        let mut first = Received::default();
        first.read(&mut s, Some(1));
        drop(s);
        let (mut s, _) = l.accept().unwrap();
        let mut second = Received::default();
        second.read(&mut s, None);
        (first, second)
    });
    // Passes for 3 s (however fast the machine, many come after the first connection is
    // gone; a write or two still succeed before the peer's reset is seen).
    let extra = ["--res", "96x64", "--time", "3", "--display-server", &addr];
    let (stderr, _) = run(render_args(&scene(&d), &d, &extra));
    let (first, second) = viewer.join().unwrap();
    assert!(!stderr.contains("gone again"), "{stderr}");
    assert_eq!((first.creates.len(), second.creates.len()), (1, 1));
    assert!(
        second.updates.contains(&[0, 0, 96, 64]),
        "{:?}",
        second.updates
    );
    assert_same(&second, &d.join("out.exr"));
}
