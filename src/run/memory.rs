//! How much memory a run may take: what the process can still use, the share a run's series
//! may take of it, the thinning of a series that would not fit, and the one refusal every
//! check that something fits gives.

use crate::scene::Scene;

/// Bytes the series of a run of `scene` take in memory (and, as text, several times that in
/// `series.csv`): each sample holds `t`, `xs`, `vs`, `a` and every ball's `x` and `v` (and its
/// `y` and `z` in a scene beyond one line), eight bytes each. Impacts add 96 bytes each,
/// which no scene's series comes near.
pub fn series_bytes(scene: &Scene) -> f64 {
    scene.sample_count() as f64 * sample_bytes(scene) as f64
}

/// Bytes one sample of `scene`'s series takes.
fn sample_bytes(scene: &Scene) -> usize {
    let per_ball = if scene.space.is_spatial() { 4 } else { 2 };
    (4 + per_ball * scene.balls.len()) * 8
}

/// Share of the memory available that a run's series may take: the rest is the model's own
/// state, the impacts and the outputs being written.
pub const MEMORY_SHARE: f64 = 0.8;

/// Memory this process can still take, bytes: the least of the machine's available memory,
/// what its control group's limit leaves, and what its address-space limit (`ulimit -v`)
/// leaves; `None` where none of them can be read (the check is then skipped).
pub fn available_memory() -> Option<f64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let field = |text: &str, key: &str| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..].split_whitespace().next()?.parse::<f64>().ok().map(|kb| kb * 1024.0)
    };
    let mut limits = vec![];
    if let Some(meminfo) = read("/proc/meminfo") {
        limits.extend(field(&meminfo, "MemAvailable:"));
    }
    if let (Some(max), Some(current)) = (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current")) {
        if let (Ok(max), Ok(current)) = (max.trim().parse::<f64>(), current.trim().parse::<f64>()) {
            limits.push((max - current).max(0.0));
        }
    }
    #[cfg(unix)]
    {
        let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
        // SAFETY: getrlimit writes into the struct it is given and reads nothing else.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } == 0 && limit.rlim_cur != libc::RLIM_INFINITY {
            let used = read("/proc/self/status").and_then(|s| field(&s, "VmSize:")).unwrap_or(0.0);
            limits.push((limit.rlim_cur as f64 - used).max(0.0));
        }
    }
    limits.into_iter().reduce(f64::min)
}

/// Whether `need` bytes fit in the memory left: `Err` with what the process can still use
/// when they take more than [`MEMORY_SHARE`] of it ([`available_memory`]). Checked before
/// anything is allocated: otherwise the allocator aborts or the kernel kills the process
/// without a word. Below 100 MB every machine the tool runs on has room, and the many short
/// runs of a study skip reading /proc.
pub fn fits_in_memory(need: f64) -> Result<(), f64> {
    if need < 1e8 {
        return Ok(());
    }
    match available_memory() {
        Some(available) if need > MEMORY_SHARE * available => Err(available),
        _ => Ok(()),
    }
}

/// Most a series is thinned to fit in memory ([`series_every`]): a series thinner than a
/// hundredth of the one asked for is not that series any more, and a scene that needs more
/// is refused with the numbers, for its user to choose the sampling.
pub const MAX_SERIES_EVERY: usize = 100;

/// The decimation rule: the series of a run of `scene` keeps every `k`-th sample, `k` the
/// smallest that makes it fit in [`MEMORY_SHARE`] of the memory left ([`fits_in_memory`]);
/// 1 when the whole series fits. Its metrics still see every sample, and `lpc run` says so.
/// `Err` with the memory left when even `k` = [`MAX_SERIES_EVERY`] would not fit.
pub fn series_every(scene: &Scene) -> Result<usize, f64> {
    let need = series_bytes(scene);
    fits_in_memory(need).map(|()| 1).or_else(|available| thinning(need, available, scene.sample_count()))
}

/// The rule of [`series_every`] for a series of `samples` samples taking `need` bytes, with
/// `available` bytes left.
fn thinning(need: f64, available: f64, samples: usize) -> Result<usize, f64> {
    let k = (need / (MEMORY_SHARE * available)).ceil();
    if k <= MAX_SERIES_EVERY as f64 {
        Ok((k as usize).clamp(1, samples.max(1)))
    } else {
        Err(available)
    }
}

/// Refuses, with the numbers, a run whose series would not fit in the memory left even
/// thinned as far as [`series_every`] goes.
pub fn check_memory(scene: &Scene) -> Result<(), String> {
    let need = series_bytes(scene);
    series_every(scene).map(|_| ()).map_err(|available| {
        let what = format!(
            "scene `{}`: its series ({} samples x {} balls, {} bytes each), even keeping one sample in {MAX_SERIES_EVERY},",
            scene.name,
            crate::scene::human(scene.sample_count() as f64),
            scene.balls.len(),
            sample_bytes(scene),
        );
        beyond_memory(need, available, &what, "raise run.sample_dt, shorten the horizon or use fewer balls")
    })
}

/// Refuses, with the numbers, what would take `need` bytes when that is more than
/// [`MEMORY_SHARE`] of the memory left ([`fits_in_memory`]): `what` names what would take it,
/// `advice` says what to do instead. Every check that something fits in memory says it so.
pub fn refuse_beyond_memory(need: f64, what: &str, advice: &str) -> Result<(), String> {
    fits_in_memory(need).map_err(|available| beyond_memory(need, available, what, advice))
}

fn beyond_memory(need: f64, available: f64, what: &str, advice: &str) -> String {
    format!(
        "{what} would take {} of memory, more than {:.0} % of the {} this process can still use; {advice}",
        bytes_for_people(need),
        100.0 * MEMORY_SHARE,
        bytes_for_people(available)
    )
}

/// `3.2 GB`, `512 MB`, `40 kB`.
pub fn bytes_for_people(b: f64) -> String {
    match b {
        b if b >= 1e12 => format!("{:.1} TB", b / 1e12),
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.0} MB", b / 1e6),
        b => format!("{:.0} kB", b / 1e3),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thinning rule: the smallest factor that fits, never past the samples there are,
    /// and a refusal past [`MAX_SERIES_EVERY`].
    #[test]
    fn a_series_thins_by_the_smallest_factor_that_fits() {
        let gb = 1e9;
        // 2.5 GB into 80 % of 1 GB: a third of the samples (0.83 GB).
        assert_eq!(thinning(2.5 * gb, gb, 5001), Ok(4));
        assert_eq!(thinning(2.4 * gb, gb, 5001), Ok(3));
        assert_eq!(thinning(80.0 * gb, gb, 5001), Ok(100));
        assert_eq!(thinning(80.1 * gb, gb, 5001), Err(gb));
        assert_eq!(thinning(10.0 * gb, gb, 3), Ok(3));
    }
}
