//! The scene's memory budget: what preparing a scene (textures now, meshes later) may allocate
//! in all, charged before each allocation so that an absurd input is refused with a clear error
//! instead of exhausting the machine.

use std::sync::atomic::{AtomicU64, Ordering};

/// The memory a render may use for its photon map unless told otherwise, in bytes (4 GiB).
pub const DEFAULT_MEMORY_LIMIT: u64 = 4 << 30;

/// A byte count in the largest binary unit that keeps it at least 1 (`4.0 GiB`).
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 { format!("{bytes} bytes") } else { format!("{value:.1} {}", UNITS[unit]) }
}

/// A budget of bytes shared by everything a scene loads. Charges are atomic, so loaders running
/// in parallel may share it; for messages that do not depend on timing, charge in file order.
#[derive(Debug)]
pub struct MemoryBudget {
    limit: u64,
    used: AtomicU64,
}

/// A charge that would take a budget past its limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "needs {}; with the {} already used, that is over the memory limit of {}",
    format_bytes(*.needed),
    format_bytes(*.used),
    format_bytes(*.limit)
)]
pub struct OverBudget {
    /// Bytes asked for.
    pub needed: u64,
    /// Bytes already charged.
    pub used: u64,
    /// The budget's limit.
    pub limit: u64,
}

impl MemoryBudget {
    /// A budget of `limit` bytes, nothing used yet.
    pub fn new(limit: u64) -> MemoryBudget {
        MemoryBudget { limit, used: AtomicU64::new(0) }
    }

    /// The limit, in bytes.
    pub fn limit(&self) -> u64 {
        self.limit
    }

    /// Bytes charged so far.
    pub fn used(&self) -> u64 {
        self.used.load(Ordering::Relaxed)
    }

    /// Bytes still free.
    pub fn remaining(&self) -> u64 {
        self.limit.saturating_sub(self.used())
    }

    /// Gives back `bytes` charged earlier (memory needed only for a while).
    pub fn release(&self, bytes: u64) {
        let _ = self
            .used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| Some(used.saturating_sub(bytes)));
    }

    /// Takes `bytes` out of the budget, or leaves it unchanged and says by how much it would go
    /// over.
    pub fn charge(&self, bytes: u64) -> Result<(), OverBudget> {
        self.used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                used.checked_add(bytes).filter(|&total| total <= self.limit)
            })
            .map(drop)
            .map_err(|used| OverBudget { needed: bytes, used, limit: self.limit })
    }
}

impl Default for MemoryBudget {
    /// [`DEFAULT_MEMORY_LIMIT`] (4 GiB).
    fn default() -> MemoryBudget {
        MemoryBudget::new(DEFAULT_MEMORY_LIMIT)
    }
}

/// Parses a byte count as people write it: `4G`, `512M`, `1.5GiB`, `800k`, `1000000` (powers of
/// 1024 for K, M, G and T, with or without `iB` or `B`).
pub fn parse_byte_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits_end = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, unit) = t.split_at(digits_end);
    let number: f64 =
        number.parse().map_err(|_| format!("`{text}` is not a size: expected e.g. 4G, 512M or 1000000"))?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        other => return Err(format!("unknown unit `{other}` in `{text}`: use K, M, G or T")),
    };
    let bytes = number * (1u64 << shift) as f64;
    if !(1.0..=u64::MAX as f64).contains(&bytes) {
        return Err(format!("`{text}` is out of range"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charges_stop_at_the_limit() {
        let budget = MemoryBudget::new(100);
        budget.charge(60).expect("fits");
        let over = budget.charge(41).expect_err("over");
        assert_eq!(over, OverBudget { needed: 41, used: 60, limit: 100 });
        assert_eq!(budget.used(), 60, "a refused charge takes nothing");
        budget.charge(40).expect("fits exactly");
        assert_eq!(budget.remaining(), 0);
        assert!(budget.charge(u64::MAX).is_err(), "no overflow");
        assert_eq!(
            over.to_string(),
            "needs 41 bytes; with the 60 bytes already used, that is over the memory limit of 100 bytes"
        );
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_byte_size("4G"), Ok(4 << 30));
        assert_eq!(parse_byte_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_byte_size("1.5g"), Ok(3 << 29));
        assert_eq!(parse_byte_size("1000"), Ok(1000));
        assert_eq!(parse_byte_size("64 kB"), Ok(64 << 10));
        assert!(parse_byte_size("lots").is_err());
        assert!(parse_byte_size("3X").is_err());
        assert!(parse_byte_size("0").is_err());
    }
}
