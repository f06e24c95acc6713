//! Interruptions and failures keep work, tested end to end with real signals
//! and processes: SIGINT and SIGTERM write the samples taken, a second signal
//! aborts without touching the output, a killed render resumes from its
//! checkpoint to the same image bit for bit, a checkpoint of something else is
//! refused, and a full or read-only disk keeps the previous file.
//!
//! The tests wait for markers (the handlers installed, as /proc shows them; a
//! checkpoint file; a line on stderr), never for fixed times.

use std::io::{BufRead, BufReader};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use raylab::film::{MetaValue, read_exr_channels, read_exr_metadata};

/// Longest wait for anything (a loaded two-core machine is slow).
const PATIENCE: Duration = Duration::from_secs(120);

/// A running `raylab`, its stderr collected as it comes.
struct Run {
    child: Child,
    stderr: Arc<Mutex<String>>,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl Run {
    fn start(args: &[&str], dir: &Path) -> Run {
        let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(args)
            .current_dir(dir)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = Arc::new(Mutex::new(String::new()));
        let pipe = child.stderr.take().unwrap();
        let sink = stderr.clone();
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines() {
                let Ok(line) = line else { break };
                let mut s = sink.lock().unwrap();
                s.push_str(&line);
                s.push('\n');
            }
        });
        Run {
            child,
            stderr,
            reader: Some(reader),
        }
    }

    fn pid(&self) -> libc::pid_t {
        self.child.id() as libc::pid_t
    }

    fn signal(&self, sig: libc::c_int) {
        // SAFETY: kill(2) on our own child.
        assert_eq!(unsafe { libc::kill(self.pid(), sig) }, 0);
    }

    fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Waits until the handlers of SIGINT and SIGTERM are installed (the
    /// render is about to start): /proc's `SigCgt` mask has their bits.
    fn wait_for_handlers(&mut self) {
        let status = format!("/proc/{}/status", self.pid());
        wait_for("the signal handlers", || {
            assert!(
                self.child.try_wait().unwrap().is_none(),
                "raylab ended early: {}",
                self.stderr()
            );
            let Ok(text) = std::fs::read_to_string(&status) else {
                return false;
            };
            let caught = text
                .lines()
                .find_map(|l| l.strip_prefix("SigCgt:"))
                .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
                .unwrap_or(0);
            let bit = |sig: libc::c_int| 1u64 << (sig - 1);
            caught & bit(libc::SIGINT) != 0 && caught & bit(libc::SIGTERM) != 0
        });
    }

    fn wait(mut self) -> (ExitStatus, String) {
        let start = Instant::now();
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s;
            }
            if start.elapsed() > PATIENCE {
                let _ = self.child.kill();
                panic!("raylab did not end: {}", self.stderr());
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        self.reader.take().unwrap().join().unwrap();
        (status, self.stderr())
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn wait_for(what: &str, mut cond: impl FnMut() -> bool) {
    let start = Instant::now();
    while !cond() {
        assert!(start.elapsed() < PATIENCE, "waited too long for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Runs `raylab` to its end.
fn run(args: &[&str], dir: &Path) -> (ExitStatus, String) {
    Run::start(args, dir).wait()
}

fn meta(path: &Path, name: &str) -> Option<MetaValue> {
    read_exr_metadata(path)
        .unwrap()
        .into_iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v)
}

fn spp_of(path: &Path) -> u32 {
    match meta(path, "raylab.spp") {
        Some(MetaValue::Int(n)) => n as u32,
        other => panic!("raylab.spp of {}: {other:?}", path.display()),
    }
}

/// Every channel of an EXR, by name, as bits.
fn bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    read_exr_channels(path)
        .unwrap()
        .channels
        .into_iter()
        .map(|c| (c.name, c.values.iter().map(|v| v.to_bits()).collect()))
        .collect()
}

fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

fn with<'a>(base: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(more).copied().collect()
}

/// The render the signal tests stop: far more samples than it will take.
const ENDLESS: &[&str] = &[
    "render",
    "cornell",
    "--integrator",
    "path",
    "--width",
    "32",
    "--height",
    "24",
    "--seed",
    "7",
    "--spp",
    "1048576",
];

/// Stops [`ENDLESS`] (plus `extra`) with `sig` and checks what it left: the
/// status, the summary, the image's metadata, and pixels equal to a render of
/// the samples taken. Returns the samples taken and the folder.
fn stop_with(sig: libc::c_int, extra: &[&str]) -> (u32, tempfile::TempDir) {
    let args = with(ENDLESS, &with(&["-o", "out.exr"], extra));
    // A signal that lands before the first pass starts (the handlers are in
    // place a moment before it) rightly stops the render with no sample and
    // no image ("interrupted before the first sample"); on a loaded machine
    // that happened in about a third of the runs. Such a run is tried again,
    // waiting longer before the signal.
    let mut attempt = 0;
    let (dir, err) = loop {
        let dir = tempfile::tempdir().unwrap();
        let mut r = Run::start(&args, dir.path());
        r.wait_for_handlers();
        std::thread::sleep(Duration::from_millis(5 << attempt));
        r.signal(sig);
        let (status, err) = r.wait();
        assert_eq!(status.signal(), Some(sig), "{status:?}: {err}");
        assert!(
            err.contains("stopping after the samples in flight"),
            "{err}"
        );
        if !err.contains("interrupted before the first sample") {
            break (dir, err);
        }
        attempt += 1;
        assert!(attempt < 6, "never past the first sample: {err}");
    };
    let out = dir.path().join("out.exr");
    let spp = spp_of(&out);
    assert!((1..1048576).contains(&spp), "{spp}");
    assert!(
        err.contains(&format!("interrupted after {spp} of 1048576 spp")),
        "{err}"
    );
    assert_eq!(
        meta(&out, "raylab.render"),
        Some(MetaValue::Text(format!(
            "spp={spp} spp_requested=1048576 seed=7 integrator=path interrupted=1"
        )))
    );
    // The image is a render of exactly those samples, bit for bit.
    let mut reference = args.clone();
    let n = spp.to_string();
    let at = reference.iter().position(|a| *a == "1048576").unwrap();
    reference[at] = &n;
    let o = reference.iter().position(|a| *a == "out.exr").unwrap();
    reference[o] = "ref.exr";
    let (status, err) = run(&reference, dir.path());
    assert!(status.success(), "{err}");
    assert_eq!(bits(&out), bits(&dir.path().join("ref.exr")));
    let Some(MetaValue::Text(info)) = meta(&dir.path().join("ref.exr"), "raylab.render") else {
        panic!("no raylab.render");
    };
    assert!(info.ends_with("interrupted=0"), "{info}");
    (spp, dir)
}

#[test]
fn sigint_writes_the_samples_taken_and_the_same_command_resumes() {
    let (spp, dir) = stop_with(libc::SIGINT, &["--aov", "albedo,depth"]);
    // The samples were saved beside the output; the same command with a few
    // more samples goes on from them, on another number of threads.
    let saved = dir.path().join(".out.exr.raylab-checkpoint");
    assert!(saved.exists(), "{:?}", files(dir.path()));
    let more = (spp + 3).to_string();
    let base = [
        "render",
        "cornell",
        "--integrator",
        "path",
        "--width",
        "32",
        "--height",
        "24",
        "--seed",
        "7",
        "--aov",
        "albedo,depth",
        "--spp",
    ];
    let (status, err) = run(
        &with(&base, &[&more, "-o", "out.exr", "--threads", "1"]),
        dir.path(),
    );
    assert!(status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "resuming from .out.exr.raylab-checkpoint: {spp} of {more} spp"
        )),
        "{err}"
    );
    assert!(!saved.exists(), "a finished render removes its checkpoint");
    let (status, err) = run(&with(&base, &[&more, "-o", "whole.exr"]), dir.path());
    assert!(status.success(), "{err}");
    assert_eq!(
        bits(&dir.path().join("out.exr")),
        bits(&dir.path().join("whole.exr"))
    );
}

#[test]
fn sigterm_writes_the_samples_taken() {
    let (_, dir) = stop_with(libc::SIGTERM, &["--threads", "1"]);
    assert!(dir.path().join(".out.exr.raylab-checkpoint").exists());
}

#[test]
fn a_second_signal_aborts_at_once_and_leaves_the_output_alone() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    std::fs::write(&out, b"the earlier image").unwrap();
    // A first pass long enough to signal twice within it.
    let mut r = Run::start(
        &[
            "render",
            "cornell",
            "--integrator",
            "path",
            "--width",
            "1200",
            "--height",
            "1200",
            "--spp",
            "64",
            "-o",
            "out.exr",
        ],
        dir.path(),
    );
    r.wait_for_handlers();
    r.signal(libc::SIGINT);
    wait_for("the first signal's message", || {
        r.stderr().contains("press Ctrl-C again to abort")
    });
    let asked = Instant::now();
    r.signal(libc::SIGINT);
    let (status, err) = r.wait();
    eprintln!(
        "aborted {:.0} ms after the second signal",
        asked.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!(status.signal(), Some(libc::SIGINT), "{err}");
    assert!(err.contains("aborted"), "{err}");
    assert!(!err.contains("wrote"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"the earlier image");
    assert_eq!(files(dir.path()), ["out.exr"]);
}

/// The render the checkpoint tests kill and resume (a few seconds whole).
const LONG: &[&str] = &[
    "render",
    "cornell",
    "--integrator",
    "path",
    "--width",
    "40",
    "--height",
    "30",
    "--seed",
    "3",
    "--spp",
    "3000",
    "--aov",
    // Not in the order `Aov::ALL` lists them: a record's sums follow this one.
    "depth,normal",
];

#[test]
fn a_killed_render_resumes_from_its_checkpoint_to_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck");
    let mut r = Run::start(
        &with(
            LONG,
            &[
                "-o",
                "out.exr",
                "--checkpoint",
                "ck",
                "--checkpoint-every",
                "0",
                "--threads",
                "2",
            ],
        ),
        dir.path(),
    );
    r.wait_for_handlers();
    wait_for("the first checkpoint", || ck.exists());
    r.signal(libc::SIGKILL);
    let (status, _) = r.wait();
    assert_eq!(status.signal(), Some(libc::SIGKILL));
    assert!(!dir.path().join("out.exr").exists());
    let saved = std::fs::read(&ck).unwrap();

    // A checkpoint of anything else is refused with one line, and kept.
    let refused: &[(&[&str], &str)] = &[
        (&["--seed", "4"], "other settings"),
        (&["--width", "41"], "other settings"),
        (&["--aov", "normal,depth"], "other settings"),
        (&["--material", "tall=mirror"], "another scene"),
    ];
    for (change, why) in refused {
        let mut args = with(LONG, &["-o", "other.exr", "--checkpoint", "ck"]);
        for pair in change.chunks(2) {
            match args.iter().position(|a| *a == pair[0]) {
                Some(i) => args[i + 1] = pair[1],
                None => args.extend_from_slice(pair),
            }
        }
        let (status, err) = run(&args, dir.path());
        assert_eq!(status.code(), Some(1), "{change:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{change:?}: {err}");
        assert!(
            err.starts_with("error: ck ") && err.contains(why),
            "{change:?}: {err}"
        );
    }
    assert_eq!(std::fs::read(&ck).unwrap(), saved);
    assert!(!dir.path().join("other.exr").exists());

    // The same render on another number of threads goes on from it.
    let (status, err) = run(
        &with(
            LONG,
            &["-o", "out.exr", "--checkpoint", "ck", "--threads", "1"],
        ),
        dir.path(),
    );
    assert!(status.success(), "{err}");
    assert!(err.contains("resuming from ck: "), "{err}");
    assert!(!ck.exists());
    let (status, err) = run(&with(LONG, &["-o", "whole.exr"]), dir.path());
    assert!(status.success(), "{err}");
    assert_eq!(spp_of(&dir.path().join("out.exr")), 3000);
    assert_eq!(
        bits(&dir.path().join("out.exr")),
        bits(&dir.path().join("whole.exr"))
    );
}

#[test]
fn a_damaged_checkpoint_gives_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let args = |ck: &str| {
        vec![
            "render",
            "--width",
            "8",
            "--height",
            "8",
            "-o",
            "out.png",
            "--checkpoint",
        ]
        .into_iter()
        .map(String::from)
        .chain([ck.to_string()])
        .collect::<Vec<_>>()
    };
    // A real checkpoint of this render (from the library), then damaged.
    std::fs::write(dir.path().join("junk"), b"not a checkpoint at all").unwrap();
    let (status, err) = run(
        &args("junk").iter().map(String::as_str).collect::<Vec<_>>(),
        dir.path(),
    );
    assert_eq!(status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("junk") && err.contains("not a raylab checkpoint"),
        "{err}"
    );

    let acc = raylab::render::Accumulator::new(8, 8, raylab::aov::AovSet::NONE);
    let key = raylab::checkpoint::Key::default();
    let ck = dir.path().join("ck");
    raylab::checkpoint::write(&ck, &key, &acc, Duration::ZERO).unwrap();
    let bytes = std::fs::read(&ck).unwrap();
    std::fs::write(&ck, &bytes[..bytes.len() - 9]).unwrap();
    let (status, err) = run(
        &args("ck").iter().map(String::as_str).collect::<Vec<_>>(),
        dir.path(),
    );
    assert_eq!(status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("truncated"), "{err}");
    // Beside the output, where nobody named it, a damaged one is only a warning.
    std::fs::rename(&ck, dir.path().join(".out.png.raylab-checkpoint")).unwrap();
    let (status, err) = run(
        &["render", "--width", "8", "--height", "8", "-o", "out.png"],
        dir.path(),
    );
    assert!(status.success(), "{err}");
    assert!(err.contains("warning: not resuming from"), "{err}");
    assert!(dir.path().join("out.png").exists());
}

/// A small tmpfs, unmounted when dropped; `None` (with the reason printed)
/// where mounting needs a root this test does not have.
struct SmallDisk {
    dir: tempfile::TempDir,
}

impl SmallDisk {
    fn mount() -> Option<SmallDisk> {
        // SAFETY: geteuid has no preconditions.
        if unsafe { libc::geteuid() } != 0 {
            eprintln!("skipped: mounting a small tmpfs needs root");
            return None;
        }
        let dir = tempfile::tempdir().unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
            .arg(dir.path())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("skipped: cannot mount a tmpfs here");
            return None;
        }
        Some(SmallDisk { dir })
    }

    fn path(&self) -> PathBuf {
        self.dir.path().to_owned()
    }

    fn remount(&self, option: &str) {
        let s = Command::new("mount")
            .args(["-o", &format!("remount,{option}")])
            .arg(self.dir.path())
            .status()
            .unwrap();
        assert!(s.success());
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

#[test]
fn a_full_or_read_only_disk_keeps_the_previous_file_and_the_samples() {
    let Some(disk) = SmallDisk::mount() else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let full = disk.path();
    for name in ["out.exr", "out.png"] {
        std::fs::write(full.join(name), b"the earlier image").unwrap();
    }
    // Fill the disk.
    let filler = vec![7u8; 1 << 20];
    let _ = std::fs::write(full.join("filler"), &filler);
    let base = [
        "render", "--width", "64", "--height", "64", "--spp", "4", "-o",
    ];
    for name in ["out.exr", "out.png"] {
        let target = full.join(name);
        let (status, err) = run(&with(&base, &[target.to_str().unwrap()]), work.path());
        assert_eq!(status.code(), Some(1), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("No space left on device"), "{err}");
        assert!(
            err.contains(&format!("the previous {} is unchanged", target.display())),
            "{err}"
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"the earlier image");
    }
    // With a checkpoint elsewhere the samples survive: the same render to
    // another output then writes them without rendering again.
    let target = full.join("out.exr");
    let ck = work.path().join("ck");
    let (status, err) = run(
        &with(
            &base,
            &[
                target.to_str().unwrap(),
                "--checkpoint",
                ck.to_str().unwrap(),
            ],
        ),
        work.path(),
    );
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(
        err.contains("ck keeps 4 spp: the same command resumes from it"),
        "{err}"
    );
    assert_eq!(std::fs::read(&target).unwrap(), b"the earlier image");
    let (status, err) = run(
        &with(
            &base,
            &["elsewhere.exr", "--checkpoint", ck.to_str().unwrap()],
        ),
        work.path(),
    );
    assert!(status.success(), "{err}");
    assert!(
        err.contains("resuming from") && err.contains("4 of 4 spp"),
        "{err}"
    );
    let (status, err) = run(&with(&base, &["whole.exr"]), work.path());
    assert!(status.success(), "{err}");
    assert_eq!(
        bits(&work.path().join("elsewhere.exr")),
        bits(&work.path().join("whole.exr"))
    );
    // A read-only disk: the same.
    std::fs::remove_file(full.join("filler")).unwrap();
    disk.remount("ro");
    let (status, err) = run(&with(&base, &[target.to_str().unwrap()]), work.path());
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(
        err.contains("Read-only file system") && err.contains("is unchanged"),
        "{err}"
    );
    assert_eq!(std::fs::read(&target).unwrap(), b"the earlier image");
    disk.remount("rw");
    // Nothing but the earlier files is left on the disk.
    assert_eq!(files(&full), ["out.exr", "out.png"]);
}
