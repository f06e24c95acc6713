//! The memory budget (`--max-memory`): an estimate of what a render will hold
//! (geometry, textures, environment map, film) checked against a ceiling
//! *before* the big allocations, so that a scene too large for the machine is
//! a one-line error rather than the kernel's OOM killer ending the process
//! halfway through a load.
//!
//! The estimates are deliberately simple per-item costs (see the constants);
//! they aim at "about", within tens of percent of what the load reports
//! afterwards, not at the byte.

use std::cell::Cell;
use std::fmt;

use thiserror::Error;

/// Estimated bytes per triangle after instancing: the triangle (48), its
/// normal (16), material and instance ids (8), its share of the BVH (about
/// 40) and of the meshes' indices and vertex attributes (about 50).
pub const GEOMETRY_BYTES_PER_TRIANGLE: u64 = 160;

/// Bytes per environment-map texel: RGB as `f32` (12) and the sampling
/// tables (running sums of rows and columns, their guides and the
/// luminance used while building them: about 12).
pub const ENVIRONMENT_BYTES_PER_TEXEL: u64 = 24;

/// Film bytes per pixel without AOVs: the image (`Vec3A`, 16) and the
/// render's exact sums (three `i128`, 48; see [`crate::fixed`]).
pub const FILM_BYTES_PER_PIXEL: u64 = 64;

/// Bytes per pixel and per AOV channel: its exact sums (16) and its averaged
/// image (4).
pub const AOV_BYTES_PER_CHANNEL: u64 = 20;

/// The default budget's share of physical memory: the rest is left to the
/// system, other programs and what the estimates leave out.
pub const DEFAULT_FRACTION: (u64, u64) = (3, 4);

/// What a render needs, by kind, in bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// Triangles, attributes and BVH.
    pub geometry: u64,
    /// Decoded texture images.
    pub textures: u64,
    /// The environment map and its sampling tables.
    pub environment: u64,
    /// The film, its sum buffer and AOVs.
    pub film: u64,
}

impl Needs {
    /// The sum of all kinds (saturating: estimates from hostile headers may be
    /// absurd).
    pub fn total(&self) -> u64 {
        self.geometry
            .saturating_add(self.textures)
            .saturating_add(self.environment)
            .saturating_add(self.film)
    }

    /// The non-zero kinds, largest first, as `textures 8.1 GiB, geometry 1.2 GiB`.
    fn breakdown(&self) -> String {
        let mut parts = [
            ("geometry", self.geometry),
            ("textures", self.textures),
            ("environment", self.environment),
            ("film", self.film),
        ];
        parts.sort_by_key(|p| std::cmp::Reverse(p.1));
        parts
            .iter()
            .filter(|(_, b)| *b > 0)
            .map(|(what, b)| format!("{what} {}", Size(*b)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A ceiling on [`Needs::total`], or none.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    limit: Option<u64>,
}

impl Default for MemoryBudget {
    /// No ceiling: a library user opts in (the command line's default is
    /// [`MemoryBudget::machine_default`]).
    fn default() -> Self {
        Self::UNLIMITED
    }
}

impl MemoryBudget {
    /// No ceiling.
    pub const UNLIMITED: Self = Self { limit: None };

    /// At most `bytes`.
    pub fn bytes(bytes: u64) -> Self {
        Self { limit: Some(bytes) }
    }

    /// [`DEFAULT_FRACTION`] of physical memory (`MemTotal` of
    /// `/proc/meminfo`); unlimited where that cannot be read.
    pub fn machine_default() -> Self {
        match physical_memory() {
            Some(total) => Self::bytes(total / DEFAULT_FRACTION.1 * DEFAULT_FRACTION.0),
            None => Self::UNLIMITED,
        }
    }

    /// The ceiling in bytes, if any.
    pub fn limit(&self) -> Option<u64> {
        self.limit
    }

    /// Whether `needs` fits; the error names `name` (the scene or the file
    /// whose header asked for the memory).
    pub fn check(&self, name: &str, needs: &Needs) -> Result<(), MemoryError> {
        match self.limit {
            Some(limit) if needs.total() > limit => Err(MemoryError {
                name: name.to_string(),
                needs: *needs,
                limit,
            }),
            _ => Ok(()),
        }
    }
}

/// A budget and what has been charged to it so far: the loaders charge each
/// big allocation (from a file's header, before decoding) and get an error
/// naming the file when the running total goes over.
#[derive(Debug, Default)]
pub struct Ledger {
    budget: MemoryBudget,
    needs: Cell<Needs>,
}

impl Ledger {
    /// An empty ledger against `budget`.
    pub fn new(budget: MemoryBudget) -> Self {
        Self {
            budget,
            needs: Cell::new(Needs::default()),
        }
    }

    /// A ledger without a ceiling (for the loaders' budget-free entry points).
    pub fn unlimited() -> Self {
        Self::new(MemoryBudget::UNLIMITED)
    }

    /// The budget.
    pub fn budget(&self) -> MemoryBudget {
        self.budget
    }

    /// Everything charged so far.
    pub fn needs(&self) -> Needs {
        self.needs.get()
    }

    /// Adds `more` if the total stays within the budget; otherwise leaves the
    /// ledger as it was and names `name` (with the whole total) in the error.
    pub fn charge(&self, name: &str, more: Needs) -> Result<(), MemoryError> {
        let n = self.needs.get();
        let total = Needs {
            geometry: n.geometry.saturating_add(more.geometry),
            textures: n.textures.saturating_add(more.textures),
            environment: n.environment.saturating_add(more.environment),
            film: n.film.saturating_add(more.film),
        };
        self.budget.check(name, &total)?;
        self.needs.set(total);
        Ok(())
    }

    /// Whether `more` would fit on top of what is charged, without charging
    /// it: for what is held only while loading (a file's bytes before they
    /// are parsed).
    pub fn fits(&self, name: &str, more: Needs) -> Result<(), MemoryError> {
        let before = self.needs.get();
        self.charge(name, more)?;
        self.needs.set(before);
        Ok(())
    }
}

/// A render would need more memory than the budget allows.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error(
    "{name}: needs about {} ({}), more than --max-memory {}",
    Size(needs.total()),
    needs.breakdown(),
    Size(*limit)
)]
pub struct MemoryError {
    /// The scene or file asking for the memory.
    pub name: String,
    /// What it needs, by kind (everything charged so far).
    pub needs: Needs,
    /// The budget.
    pub limit: u64,
}

/// Bytes shown with a binary unit and one decimal (`9.3 GiB`, `512 B`).
#[derive(Clone, Copy, Debug)]
pub struct Size(pub u64);

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
        if self.0 < 1024 {
            return write!(f, "{} B", self.0);
        }
        let mut v = self.0 as f64 / 1024.0;
        let mut unit = 0;
        while v >= 1024.0 && unit + 1 < UNITS.len() {
            v /= 1024.0;
            unit += 1;
        }
        if v.fract() == 0.0 {
            write!(f, "{v:.0} {}", UNITS[unit])
        } else {
            write!(f, "{v:.1} {}", UNITS[unit])
        }
    }
}

/// Parses a budget: `none` or `0` (no ceiling), or a size in bytes with an
/// optional binary suffix `K`, `M`, `G`, `T` (`KiB`… and `KB`… mean the
/// same), e.g. `4G`, `512M`, `1.5G`.
pub fn parse_budget(s: &str) -> Result<MemoryBudget, String> {
    let t = s.trim();
    if t.eq_ignore_ascii_case("none") {
        return Ok(MemoryBudget::UNLIMITED);
    }
    let lower = t.to_ascii_lowercase();
    let number_end = lower
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(lower.len());
    let (number, unit) = lower.split_at(number_end);
    let shift = match unit.trim() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => return Err(format!("'{s}' is not a size (e.g. 4G, 512M, or none)")),
    };
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{s}' is not a size (e.g. 4G, 512M, or none)"))?;
    let bytes = value * (1u64 << shift) as f64;
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(format!("'{s}' is too large"));
    }
    Ok(match bytes as u64 {
        0 => MemoryBudget::UNLIMITED,
        b => MemoryBudget::bytes(b),
    })
}

/// Memory this process may use, in bytes (Linux): physical memory
/// (`MemTotal` of `/proc/meminfo`), or less where a cgroup caps it (a
/// container's or a Slurm job's limit, which kills the process beyond it).
fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    let total = kib.checked_mul(1024)?;
    Some(cgroup_limit().map_or(total, |limit| limit.min(total)))
}

/// The tightest `memory.max` of this process's cgroup (v2) and its
/// ancestors, or the v1 `memory.limit_in_bytes`; `None` without one.
fn cgroup_limit() -> Option<u64> {
    let read = |path: &std::path::Path| -> Option<u64> {
        // "max" (v2) or a huge number (v1) mean no limit: they fail to parse
        // or exceed any machine's memory, and `min` with `MemTotal` sorts it.
        std::fs::read_to_string(path).ok()?.trim().parse().ok()
    };
    let root = std::path::Path::new("/sys/fs/cgroup");
    let own = std::fs::read_to_string("/proc/self/cgroup")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("0::"))
                .map(|p| p.trim_start_matches('/').to_string())
        });
    let mut limits = Vec::new();
    if let Some(own) = own {
        let mut dir = root.join(own);
        while dir.starts_with(root) {
            limits.extend(read(&dir.join("memory.max")));
            if !dir.pop() {
                break;
            }
        }
    }
    limits.extend(read(&root.join("memory/memory.limit_in_bytes")));
    limits.into_iter().min()
}

/// The film's bytes for a `width × height` image with `aov_channels` AOV
/// channels (see [`FILM_BYTES_PER_PIXEL`] and [`AOV_BYTES_PER_CHANNEL`]).
pub fn film_bytes(width: u32, height: u32, aov_channels: usize) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    pixels * (FILM_BYTES_PER_PIXEL + AOV_BYTES_PER_CHANNEL * aov_channels as u64)
}

/// Asks the kernel to back `v`'s whole capacity with 2 MiB pages (Linux's
/// transparent huge pages, `madvise(MADV_HUGEPAGE)`), for arrays read at random
/// by every ray: a BVH of tens of megabytes spans thousands of 4 KiB pages,
/// more than the TLB holds, so most node visits would also walk the page
/// tables. Call it after reserving the capacity and before writing the
/// elements: pages are given their size when first touched. Only advice:
/// without transparent huge pages, or under 4 MiB, it does nothing. (Linux's
/// default mode is often `madvise`, in which only advised memory gets them;
/// Embree advises its allocations the same way.)
pub fn advise_huge_pages<T>(v: &mut Vec<T>) {
    const HUGE: usize = 2 << 20;
    let bytes = v.capacity().saturating_mul(size_of::<T>());
    if bytes < 2 * HUGE {
        return;
    }
    #[cfg(target_os = "linux")]
    {
        // madvise wants a page-aligned start; whole pages inside the buffer only.
        // SAFETY: sysconf only reads a constant of the system.
        let page = usize::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) })
            .ok()
            .filter(|&p| p.is_power_of_two())
            .unwrap_or(4096);
        let start = v.as_mut_ptr() as usize;
        let first = start.next_multiple_of(page);
        let end = (start + bytes) / page * page;
        if end > first {
            // SAFETY: `first..end` lies inside the vector's allocation, which it
            // owns; MADV_HUGEPAGE changes how pages are backed, never their
            // contents. A failure (no THP support) leaves normal pages.
            unsafe {
                libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
            }
        }
    }
}

/// Asks for the cache line at `p` (a hint: it never faults, and `p` may point
/// anywhere).
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch reads nothing the program sees and never faults.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units_and_none() {
        let b = |s: &str| parse_budget(s).unwrap().limit();
        assert_eq!(b("4G"), Some(4 << 30));
        assert_eq!(b("512M"), Some(512 << 20));
        assert_eq!(b("512MiB"), Some(512 << 20));
        assert_eq!(b("1.5g"), Some(3 << 29));
        assert_eq!(b("1000"), Some(1000));
        assert_eq!(b("0"), None);
        assert_eq!(b("none"), None);
        for bad in ["", "G", "4X", "-1G", "1e9", "nan", "99999999999T"] {
            assert!(parse_budget(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_message_names_the_file_the_total_and_the_largest_parts_first() {
        let needs = Needs {
            geometry: 1288490189,
            textures: 8697308774,
            ..Needs::default()
        };
        let e = MemoryBudget::bytes(4 << 30)
            .check("scene.glb", &needs)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "scene.glb: needs about 9.3 GiB (textures 8.1 GiB, geometry 1.2 GiB), more than --max-memory 4 GiB"
        );
        assert!(MemoryBudget::bytes(10 << 30).check("s", &needs).is_ok());
        assert!(MemoryBudget::UNLIMITED.check("s", &needs).is_ok());
    }

    #[test]
    fn the_machine_default_is_a_fraction_of_physical_memory() {
        if let Some(total) = physical_memory() {
            let limit = MemoryBudget::machine_default().limit().unwrap();
            assert!(limit < total && limit >= total / 2, "{limit} of {total}");
        }
    }

    /// The advice reaches the kernel: the pages of an advised vector are
    /// flagged for huge pages (`hg` in `/proc/self/smaps`), whatever the
    /// machine's mode; whether the kernel then finds free 2 MiB pages is up to it.
    #[test]
    #[cfg(target_os = "linux")]
    fn advised_vectors_are_flagged_for_huge_pages() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage/enabled").exists() {
            return; // a kernel without transparent huge pages: nothing to advise
        }
        let flags_at = |addr: usize| -> String {
            let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
            let mut inside = false;
            for line in smaps.lines() {
                let range = line.split_whitespace().next().unwrap_or("");
                if let Some((lo, hi)) = range.split_once('-')
                    && let (Ok(lo), Ok(hi)) =
                        (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
                {
                    inside = (lo..hi).contains(&addr);
                } else if inside && let Some(flags) = line.strip_prefix("VmFlags:") {
                    return flags.to_string();
                }
            }
            panic!("no mapping holds {addr:#x}");
        };
        let has_hg = |flags: &str| flags.split_whitespace().any(|f| f == "hg");
        let mut big: Vec<u64> = Vec::with_capacity(16 << 17); // 16 MiB
        advise_huge_pages(&mut big);
        let page_inside = (big.as_ptr() as usize).next_multiple_of(4096) + (4 << 20);
        assert!(has_hg(&flags_at(page_inside)), "{}", flags_at(page_inside));
        big.resize(big.capacity(), 7);
        assert!(big.iter().all(|&x| x == 7));
    }
}
