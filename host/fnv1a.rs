//! FNV-1a, 64 bits: the digest of checkpoints and of the frames a run wrote.

/// FNV-1a of `bytes`: the same value on every machine and Rust version, unlike std's hasher.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}
