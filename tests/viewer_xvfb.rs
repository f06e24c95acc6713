//! The viewer for real: under Xvfb, start `raylab view`, drive it with xdotool,
//! save screenshots with P and check that each input changed the image the way it
//! says. Needs the `xvfb` and `xdotool` packages (`.ci/run` installs them); set
//! RAYLAB_SKIP_XVFB=1 to skip where they cannot be installed.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use image::RgbImage;

/// Kills the child process when dropped, so a failing test leaves nothing running.
struct Killed(Child);

impl Drop for Killed {
    /// SIGTERM first, so that Xvfb removes its `/tmp/.X<n>-lock` and socket
    /// (killed outright it leaves them, and the display numbers run out over
    /// many runs), then SIGKILL if it has not ended within two seconds.
    fn drop(&mut self) {
        if let Ok(pid) = libc::pid_t::try_from(self.0.id()) {
            // SAFETY: a plain signal to our own child, which we have not waited
            // for yet, so its pid is still ours.
            unsafe { libc::kill(pid, libc::SIGTERM) };
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(2) {
                if matches!(self.0.try_wait(), Ok(Some(_))) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn wait_for(what: &str, timeout: Duration, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(start.elapsed() < timeout, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Starts Xvfb on the first free display number.
fn start_xvfb() -> (Killed, String) {
    for n in 90..190 {
        if Path::new(&format!("/tmp/.X{n}-lock")).exists() {
            continue;
        }
        let child = Command::new("Xvfb")
            .args([
                format!(":{n}").as_str(),
                "-screen",
                "0",
                "800x600x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start Xvfb");
        let mut xvfb = Killed(child);
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{n}"));
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if socket.exists() {
                return (xvfb, format!(":{n}"));
            }
            if xvfb.0.try_wait().unwrap().is_some() {
                break; // lost a race for this display: try the next
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    panic!("could not start Xvfb on any display from :90 to :189");
}

struct Session {
    display: String,
    dir: PathBuf,
    window: String,
    shots: usize,
}

impl Session {
    fn xdotool(&self, args: &[&str]) -> String {
        let out = Command::new("timeout")
            .arg("20")
            .arg("xdotool")
            .args(args)
            .env("DISPLAY", &self.display)
            .output()
            .expect("run xdotool");
        assert!(
            out.status.success(),
            "xdotool {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    fn keys(&self, keys: &[&str]) {
        for key in keys {
            self.xdotool(&["key", "--window", &self.window, key]);
        }
    }

    /// Presses P and loads the screenshot it saves (the newest, should the
    /// press arrive twice, as xdotool's first key to a freshly focused
    /// window sometimes does).
    fn screenshot(&mut self) -> RgbImage {
        let shot = |n: usize| self.dir.join(format!("raylab-{n:04}.png"));
        let next = shot(self.shots + 1);
        self.keys(&["p"]);
        // The file appears by rename, complete.
        wait_for(&next.display().to_string(), Duration::from_secs(20), || {
            next.exists()
        });
        std::thread::sleep(Duration::from_millis(100));
        while shot(self.shots + 1).exists() {
            self.shots += 1;
        }
        image::open(shot(self.shots)).unwrap().to_rgb8()
    }
}

/// Starts Xvfb and `raylab` with `args` on it, in a fresh folder, and finds and
/// focuses its window.
fn open_viewer(args: &[&str]) -> (Killed, Killed, Session, tempfile::TempDir) {
    let (xvfb, display) = start_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let log = std::fs::File::create(dir.path().join("viewer.log")).unwrap();
    let viewer = Killed(
        Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(args)
            .current_dir(dir.path())
            .env("DISPLAY", &display)
            .stdin(Stdio::null())
            .stderr(log)
            .spawn()
            .unwrap(),
    );
    let mut s = Session {
        display,
        dir: dir.path().to_owned(),
        window: String::new(),
        shots: 0,
    };
    s.window = s
        .xdotool(&["search", "--sync", "--name", "^raylab"])
        .lines()
        .next()
        .unwrap()
        .to_string();
    s.xdotool(&["windowfocus", "--sync", &s.window]);
    (xvfb, viewer, s, dir)
}

/// The viewer tests run one at a time: each starts its own Xvfb, and two
/// starting together could settle on the same display.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Whether the viewer test may run: Xvfb and xdotool present, not skipped.
fn viewer_test_enabled() -> bool {
    if std::env::var_os("RAYLAB_SKIP_XVFB").is_some() {
        eprintln!("RAYLAB_SKIP_XVFB is set: viewer test skipped");
        return false;
    }
    assert!(
        have("Xvfb") && have("xdotool"),
        "the viewer test needs Xvfb and xdotool: apt-get install xvfb xdotool \
         (or set RAYLAB_SKIP_XVFB=1 to skip it)"
    );
    true
}

/// Mean of one channel (0 = red ...) over a rectangle.
fn mean(img: &RgbImage, x0: u32, x1: u32, y0: u32, y1: u32, channel: usize) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += img.get_pixel(x, y).0[channel] as f64;
        }
    }
    sum / ((x1 - x0) * (y1 - y0)) as f64
}

/// Centroid x and count of the tall block's blue pixels.
fn blue_block(img: &RgbImage) -> (f64, usize) {
    let (mut sx, mut n) = (0.0, 0);
    for (x, _, p) in img.enumerate_pixels() {
        let [r, g, b] = p.0;
        if b as i32 > r as i32 + 60 && b as i32 > g as i32 + 60 {
            sx += x as f64;
            n += 1;
        }
    }
    (sx / n.max(1) as f64, n)
}

#[test]
fn viewer_under_xvfb_responds_to_keys_and_mouse() {
    if !viewer_test_enabled() {
        return;
    }
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_xvfb, mut viewer, mut s, dir) =
        open_viewer(&["view", "--width", "200", "--height", "200"]);

    let base = s.screenshot();
    assert_eq!(base.dimensions(), (200, 200));
    let title = s.xdotool(&["getwindowname", &s.window]);
    assert!(
        title.contains("direct") && title.contains("ms") && title.contains("fps"),
        "{title}"
    );

    // A: the light moves left, so the left (purple) wall brightens and the right
    // (yellow) wall darkens. Measured in each wall's weak channel, which never clips.
    s.keys(&["a"; 5]);
    let lit_left = s.screenshot();
    let left = |img: &RgbImage| mean(img, 2, 25, 70, 130, 1);
    let right = |img: &RgbImage| mean(img, 175, 198, 70, 130, 2);
    assert!(
        left(&lit_left) > left(&base) + 10.0,
        "{} -> {}",
        left(&base),
        left(&lit_left)
    );
    assert!(
        right(&lit_left) < right(&base) - 5.0,
        "{} -> {}",
        right(&base),
        right(&lit_left)
    );

    // 1: flat shows the back wall's reflectance 0.75 exactly (sRGB 225).
    s.keys(&["1"]);
    let flat = s.screenshot();
    assert_eq!(flat.get_pixel(100, 60).0, [225, 225, 225]);
    assert_eq!(
        flat.get_pixel(100, 20).0,
        [108, 225, 225],
        "the ceiling is cyan"
    );
    assert!(s.xdotool(&["getwindowname", &s.window]).contains("flat"));

    // R: back to the start, and 2 back to direct: the first image again.
    s.keys(&["r", "2"]);
    let reset = s.screenshot();
    assert!((mean(&reset, 0, 200, 0, 200, 0) - mean(&base, 0, 200, 0, 200, 0)).abs() < 1.0);

    // Up: the camera moves forward, so the tall block looks bigger.
    s.keys(&["Up"; 5]);
    let closer = s.screenshot();
    let (_, n0) = blue_block(&base);
    let (_, n1) = blue_block(&closer);
    assert!(n1 as f64 > 1.3 * n0 as f64, "{n0} -> {n1} blue pixels");

    // Right: the camera turns right, so the block moves left in the image.
    s.keys(&["r", "Right", "Right"]);
    let turned = s.screenshot();
    let (x0, _) = blue_block(&base);
    let (x1, _) = blue_block(&turned);
    assert!(x1 < x0 - 10.0, "block centroid x {x0} -> {x1}");

    // Dragging the mouse right by 40 pixels also turns right (10 degrees).
    s.keys(&["r"]);
    s.xdotool(&["mousemove", "--window", &s.window, "100", "100"]);
    s.xdotool(&["mousedown", "1"]);
    s.xdotool(&["mousemove_relative", "--sync", "40", "0"]);
    s.xdotool(&["mouseup", "1"]);
    let dragged = s.screenshot();
    let (x2, _) = blue_block(&dragged);
    assert!(
        x2 < x0 - 10.0,
        "block centroid x {x0} -> {x2} after dragging"
    );

    // 3: path, exposed like direct (the same walls, about as bright); it keeps
    // accumulating while nothing moves, and a light move starts it again.
    s.keys(&["r", "3"]);
    // Samples so far, once the title shows path.
    let spp = |s: &Session| -> u32 {
        let title = s.xdotool(&["getwindowname", &s.window]);
        let n = title.rsplit(" · ").next().unwrap().trim_end_matches(" spp");
        match n.parse() {
            Ok(n) if title.contains("path") => n,
            _ => 0,
        }
    };
    wait_for("100 path samples", Duration::from_secs(60), || {
        spp(&s) >= 100
    });
    let path = s.screenshot();
    let (p, d) = (
        mean(&path, 0, 200, 0, 200, 1),
        mean(&base, 0, 200, 0, 200, 1),
    );
    assert!(p > 0.6 * d && p < 1.4 * d, "path {p} vs direct {d}");
    assert!(left(&path) > 20.0 && right(&path) > 20.0);
    s.keys(&["a"]);
    wait_for(
        "a restart after moving the light",
        Duration::from_secs(10),
        || spp(&s) < 100,
    );
    assert!(s.xdotool(&["getwindowname", &s.window]).contains("path"));
    s.keys(&["r", "2"]);

    // Resizing the window changes the render size.
    s.xdotool(&["windowsize", "--sync", &s.window, "240", "160"]);
    let resized = s.screenshot();
    assert_eq!(resized.dimensions(), (240, 160));

    // Esc quits cleanly.
    let status = quit_on_esc(&s, &mut viewer);
    let log = std::fs::read_to_string(dir.path().join("viewer.log")).unwrap();
    assert!(status.success(), "viewer exited with {status}: {log}");
    assert!(log.contains("saved raylab-0001.png"), "{log}");
}

/// Presses Esc (on the press: a release would find no window left) and
/// waits for the viewer to quit, at most 10 s.
fn quit_on_esc(s: &Session, viewer: &mut Killed) -> std::process::ExitStatus {
    s.xdotool(&["keydown", "--window", &s.window, "Escape"]);
    let start = Instant::now();
    loop {
        if let Some(status) = viewer.0.try_wait().unwrap() {
            return status;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "viewer did not quit on Esc"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The samples per pixel the title shows so far.
fn title_spp(s: &Session) -> u32 {
    let title = s.xdotool(&["getwindowname", &s.window]);
    title
        .rsplit(" · ")
        .next()
        .unwrap()
        .trim_end_matches(" spp")
        .parse()
        .unwrap_or(0)
}

#[test]
fn viewer_opens_a_gltf_scene_through_its_camera() {
    if !viewer_test_enabled() {
        return;
    }
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase/showcase.gltf");
    let scene = scene.to_str().unwrap();
    let (_xvfb, mut viewer, mut s, dir) =
        open_viewer(&["view", scene, "--width", "90", "--height", "60"]);
    // glTF scenes start with `path`.
    wait_for("path samples", Duration::from_secs(30), || {
        title_spp(&s) >= 4
    });
    let title = s.xdotool(&["getwindowname", &s.window]);
    assert!(title.contains("path") && title.contains("90×60"), "{title}");
    // Key 1: `flat`, refined to its 64 samples, shows exactly what `raylab render`
    // gives through the file's camera (the same samples, tone mapped alike).
    s.keys(&["1"]);
    wait_for("64 flat samples", Duration::from_secs(30), || {
        s.xdotool(&["getwindowname", &s.window]).contains("flat") && title_spp(&s) >= 64
    });
    let shot = s.screenshot();
    let render = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args([
            "render",
            scene,
            "--integrator",
            "flat",
            "--width",
            "90",
            "--height",
            "60",
        ])
        .args(["--spp", "64", "--quiet", "-o", "flat.png"])
        .current_dir(dir.path())
        .status()
        .unwrap();
    assert!(render.success());
    let want = image::open(dir.path().join("flat.png")).unwrap().to_rgb8();
    assert_eq!(shot.dimensions(), (90, 60));
    // f32 sums in the viewer, f64 in render: codes may differ by one.
    let worst = shot
        .as_raw()
        .iter()
        .zip(want.as_raw())
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(
        worst <= 1,
        "screenshot differs from the render by {worst} codes"
    );
    assert!(mean(&shot, 0, 90, 0, 60, 0) > 40.0, "the view is dark");
    quit_on_esc(&s, &mut viewer);
}

/// Mean absolute difference between horizontally adjacent pixels of one
/// channel over a rectangle: grain.
fn grain(img: &RgbImage, x0: u32, x1: u32, y0: u32, y1: u32) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 - 1 {
            sum += img.get_pixel(x, y).0[1].abs_diff(img.get_pixel(x + 1, y).0[1]) as f64;
        }
    }
    sum / ((x1 - x0 - 1) * (y1 - y0)) as f64
}

#[test]
fn viewer_shows_the_denoised_frame_once_the_view_rests() {
    if !viewer_test_enabled() {
        return;
    }
    // Open Image Denoise as `raylab render --denoise` finds it.
    if let Err(e) = raylab::denoise::Denoiser::new(&Default::default()) {
        assert!(
            std::env::var_os("RAYLAB_REQUIRE_OIDN").is_none_or(|v| v != "1"),
            "RAYLAB_REQUIRE_OIDN=1 but {e}"
        );
        eprintln!("skipped: {e}");
        return;
    }
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // The showcase: noisy for long enough (spot, sun and glass) that the
    // denoised frames are far smoother than the raw ones.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase/showcase.gltf");
    let (_xvfb, mut viewer, mut s, dir) = open_viewer(&[
        "view",
        scene.to_str().unwrap(),
        "--width",
        "120",
        "--height",
        "80",
        "--denoise",
    ]);
    let title = |s: &Session| s.xdotool(&["getwindowname", &s.window]);
    wait_for("a denoised frame", Duration::from_secs(30), || {
        title(&s).contains("denoised at")
    });
    let denoised = s.screenshot();
    // N: the raw progressive image again, at about as many samples.
    s.keys(&["n"]);
    wait_for("the raw image", Duration::from_secs(10), || {
        !title(&s).contains("denois")
    });
    std::thread::sleep(Duration::from_millis(300));
    let raw = s.screenshot();
    // The back wall, above the spheres: far less grain denoised.
    let (g_denoised, g_raw) = (grain(&denoised, 10, 60, 5, 25), grain(&raw, 10, 60, 5, 25));
    assert!(
        g_denoised < 0.5 * g_raw,
        "grain {g_denoised:.2} denoised against {g_raw:.2} raw (screenshots in {})",
        dir.keep().display()
    );
    // The same picture: the wall as bright either way.
    let (m_denoised, m_raw) = (
        mean(&denoised, 10, 60, 5, 25, 1),
        mean(&raw, 10, 60, 5, 25, 1),
    );
    assert!(
        (m_denoised - m_raw).abs() < 0.1 * m_raw,
        "{m_denoised} against {m_raw}"
    );
    // N again, then a move: the denoised frame goes, and comes back once the
    // view rests.
    s.keys(&["n"]);
    wait_for("a denoised frame again", Duration::from_secs(30), || {
        title(&s).contains("denoised at")
    });
    s.keys(&["Left"]);
    wait_for("the move to drop it", Duration::from_secs(10), || {
        !title(&s).contains("denoised at")
    });
    wait_for(
        "a denoised frame of the new view",
        Duration::from_secs(30),
        || title(&s).contains("denoised at"),
    );
    let status = quit_on_esc(&s, &mut viewer);
    let log = std::fs::read_to_string(dir.path().join("viewer.log")).unwrap();
    assert!(status.success(), "viewer exited with {status}: {log}");
    assert!(log.contains("denoising with OIDN"), "{log}");
}
