//! SIGINT and SIGTERM during `raylab render`: the first asks the render to
//! stop after the samples in flight (and to write what it has), the second
//! aborts at once.
//!
//! The handler only does what is async-signal-safe: it sets atomics, writes a
//! byte to a pipe (a watcher thread prints the message, so that it goes
//! through the progress bar), and on the second signal removes the temporary
//! files of writes in progress (paths prepared beforehand) and ends the
//! process by the signal.

use std::ffi::CString;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicPtr, Ordering};

/// Set by the first signal: the render stops between passes.
pub static STOP: AtomicBool = AtomicBool::new(false);
/// The first signal received (0: none).
static FIRST: AtomicI32 = AtomicI32::new(0);
/// Write end of the pipe the handler wakes the watcher through (-1: none).
static WAKE: AtomicI32 = AtomicI32::new(-1);
/// Temporary files to remove on an abort (leaked C strings, or null).
static CLEANUP: [AtomicPtr<libc::c_char>; 2] = [
    AtomicPtr::new(std::ptr::null_mut()),
    AtomicPtr::new(std::ptr::null_mut()),
];

const ABORTED: &[u8] = b"\naborted: nothing more written\n";

extern "C" fn handle(sig: libc::c_int) {
    if FIRST
        .compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst)
        .is_ok()
    {
        STOP.store(true, Ordering::SeqCst);
        let fd = WAKE.load(Ordering::SeqCst);
        if fd >= 0 {
            let byte = sig as u8;
            // SAFETY: write(2) is async-signal-safe; the buffer is one live byte.
            unsafe { libc::write(fd, (&byte as *const u8).cast(), 1) };
        }
        return;
    }
    // SAFETY: only async-signal-safe calls (unlink, write, signal, sigprocmask,
    // raise, _exit) on C strings leaked for good before the handler was set.
    unsafe {
        for slot in &CLEANUP {
            let p = slot.load(Ordering::SeqCst);
            if !p.is_null() {
                libc::unlink(p);
            }
        }
        libc::write(2, ABORTED.as_ptr().cast(), ABORTED.len());
        die(sig);
    }
}

/// Ends the process by `sig` with its default action, so that the parent sees
/// it killed by the signal (a shell reports status 128 + sig, 130 for SIGINT,
/// 143 for SIGTERM, and a script's loop stops, as for any program Ctrl-C
/// ends); `_exit(128 + sig)` if that returns.
///
/// # Safety
///
/// Async-signal-safe; callable from the handler.
unsafe fn die(sig: libc::c_int) -> ! {
    // SAFETY: plain libc calls on valid arguments.
    unsafe {
        libc::signal(sig, libc::SIG_DFL);
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, sig);
        libc::sigprocmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        libc::raise(sig);
        libc::_exit(128 + sig)
    }
}

/// Installs the handlers for SIGINT and SIGTERM, and a watcher thread that
/// calls `say` with the signal once the first one arrives.
pub fn install(say: impl Fn(libc::c_int) + Send + 'static) -> std::io::Result<()> {
    let mut fds = [0 as libc::c_int; 2];
    // SAFETY: pipe(2) fills the two descriptors.
    if unsafe { libc::pipe(fds.as_mut_ptr()) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    let read_fd = fds[0];
    WAKE.store(fds[1], Ordering::SeqCst);
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let mut byte = 0u8;
            // SAFETY: reading one byte into a live buffer from our own pipe.
            let n = unsafe { libc::read(read_fd, (&mut byte as *mut u8).cast(), 1) };
            if n == 1 {
                say(libc::c_int::from(byte));
            }
        })?;
    for sig in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: a zeroed sigaction with a handler of the right type; the
        // signal is blocked while its handler runs (the default mask).
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = handle as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            if libc::sigaction(sig, &action, std::ptr::null_mut()) != 0 {
                return Err(std::io::Error::last_os_error());
            }
        }
    }
    Ok(())
}

/// Registers the temporary files that an abort removes (of the image's and
/// the checkpoint's writes); call before [`install`].
pub fn remove_on_abort(paths: &[&Path]) {
    use std::os::unix::ffi::OsStrExt;
    for (slot, path) in CLEANUP.iter().zip(paths) {
        if let Ok(c) = CString::new(path.as_os_str().as_bytes()) {
            slot.store(c.into_raw(), Ordering::SeqCst);
        }
    }
}

/// The first signal received, if any.
pub fn received() -> Option<libc::c_int> {
    match FIRST.load(Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    }
}

/// Ends the process by the first signal received (see [`die`]), after
/// flushing standard error; returns if none was.
pub fn exit_if_received() {
    if let Some(sig) = received() {
        let _ = std::io::stderr().flush();
        // SAFETY: outside a handler, die's calls are as safe as anywhere.
        unsafe { die(sig) }
    }
}

/// The signal's name, for messages.
pub fn name(sig: libc::c_int) -> &'static str {
    match sig {
        libc::SIGINT => "SIGINT",
        libc::SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}
