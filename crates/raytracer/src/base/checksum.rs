//! The checksum that tells a damaged file: checkpoints' records and part files.

/// The 64-bit FNV-1a hash: enough to tell a damaged file (not an adversary's).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Adds `bytes` to the hash.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// Adds a piece of text with its length before it (so that `ab` + `c` differs from `a` + `bc`).
    pub fn write_text(&mut self, text: &str) {
        self.write(&(text.len() as u64).to_le_bytes());
        self.write(text.as_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_and_lengths_kept_apart() {
        // The FNV-1a test vectors.
        assert_eq!(Fnv::default().0, 0xcbf2_9ce4_8422_2325);
        let mut h = Fnv::default();
        h.write(b"a");
        assert_eq!(h.0, 0xaf63_dc4c_8601_ec8c);
        let (mut x, mut y) = (Fnv::default(), Fnv::default());
        x.write_text("ab");
        x.write_text("c");
        y.write_text("a");
        y.write_text("bc");
        assert_ne!(x.0, y.0);
    }
}
