//! Intel Open Image Denoise (OIDN) 2.x, loaded at run time.
//!
//! raylab never links OIDN: `cargo build` and `cargo test` work without it,
//! and one binary runs on machines with and without it. The library is opened
//! with `dlopen` ([`libloading`]) when a denoiser is asked for, from the first
//! place of [`search_order`] that has it, and its C API is called through the
//! function pointers looked up here. Every call is followed by a look at the
//! device's error (`oidnGetDeviceError`), so an OIDN failure becomes one
//! [`OidnError`] naming the call.

use std::ffi::{CStr, CString, OsString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use thiserror::Error;

/// The environment variable that names the OIDN library to use (a file), or
/// a folder that holds it; when set, nothing else is searched.
pub const ENV_VAR: &str = "RAYLAB_OIDN";

/// The oldest OIDN accepted: 2.0 brought the `quality` parameter and the
/// device API used here.
pub const MIN_VERSION: i32 = 2_00_00;

/// The library's file name on this platform (major version 2).
#[cfg(target_os = "linux")]
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";
/// The library's file name on this platform (major version 2).
#[cfg(target_os = "macos")]
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.2.dylib";
/// The library's file name on this platform (major version 2).
#[cfg(target_os = "windows")]
pub const LIBRARY_NAME: &str = "OpenImageDenoise.dll";
/// The library's file name on this platform (major version 2).
#[cfg(not(any(target_os = "linux", target_os = "macos", target_os = "windows")))]
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";

/// How to install OIDN, for messages.
pub const INSTALL_HINT: &str = "install it with `pip install pyoidn` (it ships the library), or set RAYLAB_OIDN to the library file";

/// Why OIDN could not be used.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum OidnError {
    /// No library was found where [`search_order`] looks.
    #[error("Open Image Denoise 2.x ({LIBRARY_NAME}) was not found ({looked}); {INSTALL_HINT}")]
    NotFound {
        /// Where it was looked for, in words.
        looked: String,
    },
    /// A library was found but could not be loaded or lacks the API.
    #[error("cannot load Open Image Denoise from {}: {message}; {INSTALL_HINT}", path.display())]
    Load {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The library is older than [`MIN_VERSION`].
    #[error("Open Image Denoise {found} at {} is too old: raylab needs 2.0 or newer; {INSTALL_HINT}", path.display())]
    TooOld {
        /// The file.
        path: PathBuf,
        /// Its version, `major.minor.patch`.
        found: String,
    },
    /// A call into the library failed.
    #[error("Open Image Denoise: {call} failed: {message}")]
    Call {
        /// The API function.
        call: &'static str,
        /// OIDN's own message.
        message: String,
    },
}

/// Where the library is looked for, in order:
///
/// 1. `RAYLAB_OIDN`, if set: that file, or [`LIBRARY_NAME`] in that folder
///    (and nothing else, so that a user can pin a version);
/// 2. the system's library search path (`LD_LIBRARY_PATH`, the `ld.so`
///    cache: wherever `dlopen` finds [`LIBRARY_NAME`]);
/// 3. the library that PyPI's `pyoidn` wheel installs
///    (`site-packages/pyoidn/oidn/lib/`): in the active virtual environment
///    (`VIRTUAL_ENV`), the user's site-packages (`~/.local`), then wherever
///    `python3` finds the `pyoidn` package.
///
/// The first two are returned as [`Candidate`]s here; the `python3` lookup
/// runs only if everything before it fails (see [`Library::find`]).
pub fn search_order() -> Vec<Candidate> {
    if let Some(pinned) = std::env::var_os(ENV_VAR).filter(|v| !v.is_empty()) {
        return vec![Candidate::Pinned(PathBuf::from(pinned))];
    }
    let mut list = vec![Candidate::System];
    let mut roots: Vec<PathBuf> = Vec::new();
    if let Some(venv) = std::env::var_os("VIRTUAL_ENV").filter(|v| !v.is_empty()) {
        roots.push(PathBuf::from(venv).join("lib"));
    }
    if let Some(home) = std::env::var_os("HOME").filter(|v| !v.is_empty()) {
        roots.push(PathBuf::from(home).join(".local").join("lib"));
    }
    for root in roots {
        // lib/python3.X/site-packages/pyoidn/oidn/lib
        let Ok(entries) = std::fs::read_dir(&root) else {
            continue;
        };
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with("python3"))
            .map(|e| pyoidn_lib_dir(&e.path().join("site-packages").join("pyoidn")))
            .filter(|dir| dir.join(LIBRARY_NAME).is_file())
            .collect();
        found.sort();
        list.extend(found.into_iter().rev().map(Candidate::Folder));
    }
    list.push(Candidate::Python);
    list
}

/// The folder of the OIDN libraries inside the `pyoidn` package folder.
fn pyoidn_lib_dir(package: &Path) -> PathBuf {
    let sub = if cfg!(windows) { "bin" } else { "lib" };
    package.join("oidn").join(sub)
}

/// One place [`search_order`] looks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Candidate {
    /// `RAYLAB_OIDN`: a file or a folder.
    Pinned(PathBuf),
    /// `dlopen` by name.
    System,
    /// A folder that holds [`LIBRARY_NAME`].
    Folder(PathBuf),
    /// Ask `python3` where the `pyoidn` package is.
    Python,
}

impl Candidate {
    fn describe(&self) -> String {
        match self {
            Candidate::Pinned(p) => format!("{ENV_VAR}={}", p.display()),
            Candidate::System => "the system's library path".into(),
            Candidate::Folder(p) => p.display().to_string(),
            Candidate::Python => "python3's pyoidn package".into(),
        }
    }

    /// The file to open, or the name to give `dlopen`; `None` where there is
    /// nothing to try.
    fn target(&self) -> Option<OsString> {
        match self {
            Candidate::Pinned(p) if p.is_dir() => Some(p.join(LIBRARY_NAME).into_os_string()),
            Candidate::Pinned(p) => Some(p.clone().into_os_string()),
            Candidate::System => Some(LIBRARY_NAME.into()),
            Candidate::Folder(p) => Some(p.join(LIBRARY_NAME).into_os_string()),
            Candidate::Python => python_pyoidn().map(|p| p.join(LIBRARY_NAME).into_os_string()),
        }
    }
}

/// The `pyoidn` library folder of whatever environment `python3` runs in,
/// found without importing the package (which would load OIDN into Python).
fn python_pyoidn() -> Option<PathBuf> {
    let script = "import importlib.util as u\ns = u.find_spec('pyoidn')\nprint(s.submodule_search_locations[0] if s and s.submodule_search_locations else '')";
    let out = std::process::Command::new("python3")
        .args(["-I", "-c", script])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    let package = text.trim();
    if !out.status.success() || package.is_empty() {
        return None;
    }
    Some(pyoidn_lib_dir(Path::new(package)))
}

// The C API's types: handles are opaque pointers, enums are C ints.
type Handle = *mut c_void;
const DEVICE_TYPE_CPU: c_int = 1;
const FORMAT_FLOAT3: c_int = 3;
const ERROR_NONE: c_int = 0;

/// The OIDN quality modes (`OIDNQuality`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quality {
    /// For final frames (OIDN's default).
    High,
    /// Faster, for interactive use.
    Balanced,
    /// Fastest, for previews (OIDN 2.3 and newer; older ones use
    /// [`Quality::Balanced`]).
    Fast,
}

impl Quality {
    fn code(self, version: i32) -> c_int {
        match self {
            Quality::High => 6,
            Quality::Balanced => 5,
            Quality::Fast if version >= 2_03_00 => 4,
            Quality::Fast => 5,
        }
    }
}

/// The API functions raylab calls, looked up once.
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    set_device_int: unsafe extern "C" fn(Handle, *const c_char, c_int),
    set_device_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    get_device_int: unsafe extern "C" fn(Handle, *const c_char) -> c_int,
    get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int,
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_shared_filter_image: unsafe extern "C" fn(
        Handle,
        *const c_char,
        *mut c_void,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    unset_filter_image: unsafe extern "C" fn(Handle, *const c_char),
    set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    set_filter_int: unsafe extern "C" fn(Handle, *const c_char, c_int),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// The OIDN library, opened.
pub struct Library {
    api: Api,
    path: PathBuf,
    // Kept open for as long as `api`'s pointers are used.
    _lib: libloading::Library,
}

impl std::fmt::Debug for Library {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Library").field("path", &self.path).finish()
    }
}

impl Library {
    /// Opens the first library of [`search_order`] that loads.
    pub fn find() -> Result<Library, OidnError> {
        let mut looked = Vec::new();
        let mut load_error = None;
        for candidate in search_order() {
            looked.push(candidate.describe());
            let Some(target) = candidate.target() else {
                continue;
            };
            let path = PathBuf::from(&target);
            // A file that is not there is "not found"; one that is there but
            // does not load is reported (a broken install should be fixed,
            // not silently skipped), unless a later place has a good one.
            let named = !matches!(candidate, Candidate::System);
            if named && !path.is_file() {
                continue;
            }
            match Library::open_target(&target) {
                Ok(lib) => return Ok(lib),
                Err(e) if named => {
                    load_error.get_or_insert(e);
                }
                Err(_) => {}
            }
        }
        Err(load_error.unwrap_or(OidnError::NotFound {
            looked: format!("looked in {}", looked.join(", ")),
        }))
    }

    /// Opens the library at `path` (a file).
    pub fn open(path: &Path) -> Result<Library, OidnError> {
        Library::open_target(path.as_os_str())
    }

    fn open_target(target: &std::ffi::OsStr) -> Result<Library, OidnError> {
        let path = PathBuf::from(target);
        let load = |message: String| OidnError::Load {
            path: path.clone(),
            message,
        };
        // SAFETY: opening a library runs its initialisers; OIDN's only set up
        // its own state.
        let lib = unsafe { libloading::Library::new(target) }.map_err(|e| load(e.to_string()))?;
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the symbol has the signature of the OIDN 2.x C API
                // (`oidn.h`), which the field's type spells out.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|e| load(format!("it has no {} ({e})", $name)))?
            };
        }
        let api = Api {
            new_device: sym!("oidnNewDevice"),
            commit_device: sym!("oidnCommitDevice"),
            release_device: sym!("oidnReleaseDevice"),
            set_device_int: sym!("oidnSetDeviceInt"),
            set_device_bool: sym!("oidnSetDeviceBool"),
            get_device_int: sym!("oidnGetDeviceInt"),
            get_device_error: sym!("oidnGetDeviceError"),
            new_filter: sym!("oidnNewFilter"),
            set_shared_filter_image: sym!("oidnSetSharedFilterImage"),
            unset_filter_image: sym!("oidnUnsetFilterImage"),
            set_filter_bool: sym!("oidnSetFilterBool"),
            set_filter_int: sym!("oidnSetFilterInt"),
            commit_filter: sym!("oidnCommitFilter"),
            execute_filter: sym!("oidnExecuteFilter"),
            release_filter: sym!("oidnReleaseFilter"),
        };
        // Where `dlopen` found it, for messages and the summary line.
        let path = loaded_path(&lib, api.new_device as *const c_void).unwrap_or(path);
        Ok(Library {
            api,
            path,
            _lib: lib,
        })
    }

    /// The file the library was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The file that holds `symbol` (via `dladdr`), if the platform says.
#[cfg(unix)]
fn loaded_path(_lib: &libloading::Library, symbol: *const c_void) -> Option<PathBuf> {
    use std::os::unix::ffi::OsStrExt;
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    // SAFETY: `dladdr` only reads the address and fills `info`.
    if unsafe { libc::dladdr(symbol, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: `dli_fname` is a NUL-terminated string owned by the loader.
    let name = unsafe { CStr::from_ptr(info.dli_fname) };
    Some(PathBuf::from(std::ffi::OsStr::from_bytes(name.to_bytes())))
}

#[cfg(not(unix))]
fn loaded_path(_lib: &libloading::Library, _symbol: *const c_void) -> Option<PathBuf> {
    None
}

/// A committed CPU device.
pub struct Device {
    lib: Arc<Library>,
    handle: Handle,
    /// `major * 10000 + minor * 100 + patch`.
    version: i32,
    threads: usize,
}

// SAFETY: an OIDN device may be used from any thread (its API calls are
// thread-safe); raylab uses each from one thread at a time (`&mut self`).
unsafe impl Send for Device {}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device")
            .field("library", &self.lib.path)
            .field("version", &self.version_string())
            .field("threads", &self.threads)
            .finish()
    }
}

fn cstr(s: &str) -> CString {
    CString::new(s).expect("no NUL in OIDN parameter names")
}

impl Device {
    /// A CPU device of `lib` running `threads` threads (0: OIDN's choice, one
    /// per core), with thread pinning off (raylab's own threads may run
    /// beside it).
    pub fn cpu(lib: Arc<Library>, threads: usize) -> Result<Device, OidnError> {
        let api = &lib.api;
        // SAFETY: the C API as documented; the handle is checked before use.
        let handle = unsafe { (api.new_device)(DEVICE_TYPE_CPU) };
        if handle.is_null() {
            // A device that could not be made reports on the null device.
            return Err(
                error_of(api, std::ptr::null_mut(), "oidnNewDevice").unwrap_or_else(|| {
                    OidnError::Call {
                        call: "oidnNewDevice",
                        message: "no CPU device (the CPU may lack SSE4.1)".into(),
                    }
                }),
            );
        }
        let mut device = Device {
            lib: lib.clone(),
            handle,
            version: 0,
            threads,
        };
        let threads_c = c_int::try_from(threads).unwrap_or(c_int::MAX);
        // SAFETY: a live device; names are NUL-terminated.
        unsafe {
            (api.set_device_int)(handle, cstr("numThreads").as_ptr(), threads_c);
        }
        device.check("oidnSetDeviceInt(numThreads)")?;
        unsafe { (api.set_device_bool)(handle, cstr("setAffinity").as_ptr(), false) };
        device.check("oidnSetDeviceBool(setAffinity)")?;
        unsafe { (api.commit_device)(handle) };
        device.check("oidnCommitDevice")?;
        device.version = unsafe { (api.get_device_int)(handle, cstr("version").as_ptr()) };
        device.check("oidnGetDeviceInt(version)")?;
        if device.version < MIN_VERSION {
            return Err(OidnError::TooOld {
                path: lib.path.clone(),
                found: device.version_string(),
            });
        }
        Ok(device)
    }

    /// The error OIDN recorded since the last check, naming `call`.
    fn check(&self, call: &'static str) -> Result<(), OidnError> {
        match error_of(&self.lib.api, self.handle, call) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// `major.minor.patch`.
    pub fn version_string(&self) -> String {
        let v = self.version;
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// The library this device came from.
    pub fn library(&self) -> &Library {
        &self.lib
    }

    /// Threads asked for (0: one per core).
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// A new `RT` filter. (OIDN counts references: a filter keeps its device
    /// alive inside the library even after [`Device`] is dropped.)
    pub fn filter(&self) -> Result<Filter, OidnError> {
        let api = &self.lib.api;
        // SAFETY: a live device; the name is NUL-terminated.
        let handle = unsafe { (api.new_filter)(self.handle, cstr("RT").as_ptr()) };
        self.check("oidnNewFilter(RT)")?;
        if handle.is_null() {
            return Err(OidnError::Call {
                call: "oidnNewFilter(RT)",
                message: "no filter made".into(),
            });
        }
        Ok(Filter {
            lib: self.lib.clone(),
            device: self.handle,
            version: self.version,
            handle,
        })
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: a live device, released once (filters hold their own
        // reference inside OIDN).
        unsafe { (self.lib.api.release_device)(self.handle) };
    }
}

/// OIDN's error since the last query on `device` (null: this thread's),
/// if there is one.
fn error_of(api: &Api, device: Handle, call: &'static str) -> Option<OidnError> {
    let mut message: *const c_char = std::ptr::null();
    // SAFETY: `oidnGetDeviceError` accepts a null device and writes a pointer
    // to a NUL-terminated string it owns (valid until the next call).
    let code = unsafe { (api.get_device_error)(device, &mut message) };
    if code == ERROR_NONE {
        return None;
    }
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: see above.
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    let kind = match code {
        1 => "unknown error",
        2 => "invalid argument",
        3 => "invalid operation",
        4 => "out of memory",
        5 => "unsupported hardware",
        6 => "cancelled",
        _ => "error",
    };
    let message = if text.is_empty() {
        kind.to_string()
    } else {
        format!("{text} ({kind})")
    };
    Some(OidnError::Call { call, message })
}

/// An `RT` filter of a [`Device`], its images shared with the caller.
pub struct Filter {
    lib: Arc<Library>,
    device: Handle,
    version: i32,
    handle: Handle,
}

// SAFETY: as for `Device`.
unsafe impl Send for Filter {}

/// The images of one filter run: `width × height` RGB triples, row-major.
pub struct Images<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The main input (`color`, or `albedo`/`normal` when prefiltering a
    /// guide), by the name OIDN gives it.
    pub input: (&'static str, &'a [f32]),
    /// Guides for the main input: (`albedo`, values), (`normal`, values).
    pub guides: Vec<(&'static str, &'a [f32])>,
    /// Where the result goes.
    pub output: &'a mut [f32],
}

/// Settings of one filter run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSettings {
    /// The main input is HDR (radiance); false for a guide.
    pub hdr: bool,
    /// The guides are free of noise (`cleanAux`).
    pub clean_aux: bool,
    /// Quality mode.
    pub quality: Quality,
}

impl Filter {
    fn check(&self, call: &'static str) -> Result<(), OidnError> {
        match error_of(&self.lib.api, self.device, call) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Runs the filter on `images`.
    pub fn run(&mut self, images: Images<'_>, settings: FilterSettings) -> Result<(), OidnError> {
        let n = images.width * images.height * 3;
        let all_sized = std::iter::once(images.input.1)
            .chain(images.guides.iter().map(|g| g.1))
            .all(|v| v.len() == n)
            && images.output.len() == n;
        if !all_sized || n == 0 {
            return Err(OidnError::Call {
                call: "oidnSetSharedFilterImage",
                message: format!(
                    "images of {}×{} pixels need {n} values each",
                    images.width, images.height
                ),
            });
        }
        let api = &self.lib.api;
        let h = self.handle;
        let d = &*self;
        let set = |name: &'static str, data: *const f32| {
            // SAFETY: `data` holds `width × height` packed RGB f32 triples
            // (checked above) and outlives the filter's execution below; OIDN
            // only reads inputs and writes `output`.
            unsafe {
                (api.set_shared_filter_image)(
                    h,
                    cstr(name).as_ptr(),
                    data as *mut c_void,
                    FORMAT_FLOAT3,
                    images.width,
                    images.height,
                    0,
                    0,
                    0,
                )
            };
            d.check("oidnSetSharedFilterImage")
        };
        // A filter may have held other images before: only these count.
        for name in ["color", "albedo", "normal"] {
            unsafe { (api.unset_filter_image)(h, cstr(name).as_ptr()) };
            d.check("oidnUnsetFilterImage")?;
        }
        set(images.input.0, images.input.1.as_ptr())?;
        for (name, values) in &images.guides {
            set(name, values.as_ptr())?;
        }
        set("output", images.output.as_mut_ptr())?;
        unsafe {
            (api.set_filter_bool)(h, cstr("hdr").as_ptr(), settings.hdr);
        }
        d.check("oidnSetFilterBool(hdr)")?;
        unsafe { (api.set_filter_bool)(h, cstr("cleanAux").as_ptr(), settings.clean_aux) };
        d.check("oidnSetFilterBool(cleanAux)")?;
        let quality = settings.quality.code(self.version);
        unsafe { (api.set_filter_int)(h, cstr("quality").as_ptr(), quality) };
        d.check("oidnSetFilterInt(quality)")?;
        unsafe { (api.commit_filter)(h) };
        d.check("oidnCommitFilter")?;
        unsafe { (api.execute_filter)(h) };
        d.check("oidnExecuteFilter")
    }
}

impl Drop for Filter {
    fn drop(&mut self) {
        // SAFETY: a live filter, released once.
        unsafe { (self.lib.api.release_filter)(self.handle) };
    }
}
