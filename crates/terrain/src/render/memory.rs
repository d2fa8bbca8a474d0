//! The memory at hand for GPU resources on a software adapter, whose "GPU" memory is this
//! process's own: the least of what the system has free (`MemAvailable`) and the room left
//! under the address-space limit (`ulimit -v`). Linux only; elsewhere nothing is known.

/// Bytes at hand and which limit gives them, or `None` when nothing is known.
pub fn at_hand() -> Option<(u64, &'static str)> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let status = std::fs::read_to_string("/proc/self/status").ok();
    smallest(
        meminfo.as_deref().and_then(mem_available),
        limits.as_deref().and_then(address_space_limit),
        status.as_deref().and_then(address_space_used),
    )
}

/// The least of the free memory and the room under the address-space limit.
fn smallest(free: Option<u64>, limit: Option<u64>, used: Option<u64>) -> Option<(u64, &'static str)> {
    let room = limit.map(|limit| limit.saturating_sub(used.unwrap_or(0)));
    match (free, room) {
        (Some(free), Some(room)) if room < free => Some((room, "are left in the address space (ulimit -v)")),
        (Some(free), _) => Some((free, "are free on this machine")),
        (None, Some(room)) => Some((room, "are left in the address space (ulimit -v)")),
        (None, None) => None,
    }
}

/// `MemAvailable` of `/proc/meminfo`, in bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    kilobytes_field(meminfo, "MemAvailable:")
}

/// The address space in use (`VmSize` of `/proc/self/status`), in bytes.
fn address_space_used(status: &str) -> Option<u64> {
    kilobytes_field(status, "VmSize:")
}

fn kilobytes_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|line| line.starts_with(name))?;
    let kilobytes: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kilobytes.saturating_mul(1024))
}

/// The soft limit of "Max address space" in `/proc/self/limits`, in bytes (`None` when
/// unlimited).
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits.lines().find(|line| line.starts_with("Max address space"))?;
    line["Max address space".len()..].split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: &str = "Limit                     Soft Limit           Hard Limit           Units     \n\
        Max cpu time              unlimited            unlimited            seconds   \n\
        Max address space         8192000000           unlimited            bytes     \n";

    #[test]
    fn reads_the_kernels_tables() {
        assert_eq!(address_space_limit(LIMITS), Some(8_192_000_000));
        assert_eq!(address_space_limit(&LIMITS.replace("8192000000", "unlimited")), None);
        assert_eq!(mem_available("MemTotal:  2000 kB\nMemAvailable:   1500 kB\n"), Some(1_536_000));
        assert_eq!(address_space_used("Name:\tx\nVmSize:\t  4000 kB\n"), Some(4_096_000));
        assert_eq!(mem_available("MemTotal: 2000 kB\n"), None);
    }

    #[test]
    fn the_tighter_limit_wins() {
        assert_eq!(smallest(Some(100), Some(300), Some(250)).map(|(b, _)| b), Some(50));
        assert_eq!(smallest(Some(100), Some(300), Some(50)).map(|(b, _)| b), Some(100));
        assert_eq!(smallest(Some(100), None, Some(50)).map(|(b, _)| b), Some(100));
        assert_eq!(smallest(None, Some(300), None).map(|(b, _)| b), Some(300));
        assert_eq!(smallest(None, None, None), None);
        assert!(smallest(Some(100), Some(300), Some(250)).is_some_and(|(_, why)| why.contains("ulimit")));
    }

    #[test]
    fn this_process_has_some_memory_at_hand() {
        if cfg!(target_os = "linux") {
            assert!(at_hand().is_some_and(|(bytes, _)| bytes > 0));
        }
    }
}
