//! A faulty serial line: flips and drops bytes at given rates and corrupts runs of bytes (bursts,
//! as noise from a motor would; seeded, so runs repeat), and a pacer that makes bytes take the time they take at a baud rate (8N1: 10 bits a byte).

use rand::{Rng, RngExt, SeedableRng};
use rand_xoshiro::SplitMix64;
use std::time::{Duration, Instant};

/// Fault rates of one direction of the line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LineConfig {
    /// Fraction of bytes replaced by a different byte.
    pub flip_rate: f64,
    /// Fraction of bytes lost.
    pub drop_rate: f64,
    /// Fraction of bytes that start a burst: this byte and the next `burst_len - 1` are all
    /// replaced by different bytes.
    pub burst_rate: f64,
    /// Bytes corrupted by one burst.
    pub burst_len: u32,
    /// Seed of the fault pattern.
    pub seed: u64,
}

/// What the line did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineStats {
    /// Bytes offered.
    pub bytes: u64,
    /// Bytes changed.
    pub flipped: u64,
    /// Bytes lost.
    pub dropped: u64,
    /// Bursts started.
    pub bursts: u64,
}

/// One direction of a line.
#[derive(Clone, Debug)]
pub struct FaultyLine {
    config: LineConfig,
    faults: SplitMix64,
    stats: LineStats,
    /// Bytes of the current burst still to corrupt.
    burst_left: u32,
}

impl FaultyLine {
    /// A line with these rates.
    pub fn new(config: LineConfig) -> Self {
        FaultyLine {
            config,
            // SplitMix64, the generator of `needle_sim::random` (seeded directly): neighbouring
            // seeds give unrelated fault patterns.
            faults: SplitMix64::seed_from_u64(config.seed),
            stats: LineStats::default(),
            burst_left: 0,
        }
    }

    /// A perfect line.
    pub fn clean() -> Self {
        Self::new(LineConfig::default())
    }

    /// Counters so far.
    pub fn stats(&self) -> LineStats {
        self.stats
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.faults.random::<f64>() < p
    }

    /// Carries `bytes` across the line, appending what arrives to `out`.
    pub fn carry(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        for &b in bytes {
            self.stats.bytes += 1;
            if self.burst_left == 0 && self.chance(self.config.burst_rate) {
                self.stats.bursts += 1;
                self.burst_left = self.config.burst_len;
            }
            if self.burst_left > 0 {
                self.burst_left -= 1;
                self.stats.flipped += 1;
                out.push(b ^ ((self.faults.next_u64() % 255) as u8 + 1));
                continue;
            }
            if self.chance(self.config.drop_rate) {
                self.stats.dropped += 1;
                continue;
            }
            if self.chance(self.config.flip_rate) {
                self.stats.flipped += 1;
                // XOR with a non-zero mask: the byte always changes.
                out.push(b ^ ((self.faults.next_u64() % 255) as u8 + 1));
                continue;
            }
            out.push(b);
        }
    }
}

/// Makes bytes take their time on the line: `wait(n)` returns when `n` more bytes would have
/// been shifted out at the baud rate, back to back with the previous ones.
#[derive(Clone, Debug)]
pub struct Pacer {
    byte_time: Option<Duration>,
    free_at: Instant,
}

impl Pacer {
    /// Pacing at `baud` (8N1), or none.
    pub fn new(baud: Option<u32>) -> Self {
        Pacer {
            byte_time: baud
                .filter(|&b| b > 0)
                .map(|b| Duration::from_secs_f64(10.0 / f64::from(b))),
            free_at: Instant::now(),
        }
    }

    /// Sleeps until `n` bytes have been carried.
    pub fn wait(&mut self, n: usize) {
        let Some(t) = self.byte_time else { return };
        let now = Instant::now();
        let start = self.free_at.max(now);
        self.free_at = start + t * n as u32;
        if self.free_at > now {
            std::thread::sleep(self.free_at - now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_seeds_are_honoured() {
        let cfg = LineConfig {
            flip_rate: 0.01,
            drop_rate: 0.01,
            seed: 7,
            ..LineConfig::default()
        };
        let data = vec![0x5A; 200_000];
        let (mut a, mut b) = (FaultyLine::new(cfg), FaultyLine::new(cfg));
        let (mut out_a, mut out_b) = (Vec::new(), Vec::new());
        a.carry(&data, &mut out_a);
        b.carry(&data, &mut out_b);
        assert_eq!(out_a, out_b, "same seed, same faults");
        let s = a.stats();
        assert_eq!(out_a.len() as u64, s.bytes - s.dropped);
        assert_eq!(
            out_a.iter().filter(|&&x| x != 0x5A).count() as u64,
            s.flipped
        );
        for n in [s.flipped, s.dropped] {
            assert!((1700..2300).contains(&n), "{s:?}");
        }
        let mut c = FaultyLine::new(LineConfig { seed: 8, ..cfg });
        let mut out_c = Vec::new();
        c.carry(&data, &mut out_c);
        assert_ne!(out_a, out_c);
    }

    #[test]
    fn bursts_corrupt_runs_of_bytes() {
        let cfg = LineConfig {
            burst_rate: 0.001,
            burst_len: 20,
            seed: 3,
            ..LineConfig::default()
        };
        let data = vec![0x5A; 100_000];
        let mut line = FaultyLine::new(cfg);
        let mut out = Vec::new();
        line.carry(&data, &mut out);
        let s = line.stats();
        assert_eq!(out.len(), data.len(), "bursts corrupt, they do not drop");
        assert!((60..140).contains(&s.bursts), "{s:?}");
        // Every corrupted byte lies in a run of 20 (runs may touch).
        let bad: Vec<bool> = out.iter().map(|&x| x != 0x5A).collect();
        assert_eq!(bad.iter().filter(|&&x| x).count() as u64, s.flipped);
        assert_eq!(s.flipped, 20 * s.bursts);
        let mut run = 0;
        for (i, &b) in bad.iter().enumerate() {
            if b {
                run += 1;
            }
            if !b || i + 1 == bad.len() {
                assert!(
                    run % 20 == 0,
                    "a run of {run} corrupted bytes ending at {i}"
                );
                run = 0;
            }
        }
    }

    #[test]
    fn a_clean_line_is_clean() {
        let mut l = FaultyLine::clean();
        let mut out = Vec::new();
        l.carry(b"hello", &mut out);
        assert_eq!(out, b"hello");
    }
}
