//! A small seeded generator (PCG32, O'Neill 2014): the RRT must give the same tree for the same
//! seed on every machine, so it owns its generator instead of depending on a crate's defaults.

/// PCG-XSH-RR 64/32.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

const MUL: u64 = 6364136223846793005;

impl Pcg32 {
    /// A generator for `seed` (any value; stream fixed).
    pub fn new(seed: u64) -> Pcg32 {
        let mut g = Pcg32 {
            state: 0,
            inc: (0xda3e_39cb_94b9_5bdb << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(seed);
        g.next_u32();
        g
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        let hi = u64::from(self.next_u32()) << 21;
        let lo = u64::from(self.next_u32() >> 11);
        (hi | lo) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream_and_seeds_differ() {
        let a: Vec<u32> = (0..8)
            .scan(Pcg32::new(42), |g, _| Some(g.next_u32()))
            .collect();
        let b: Vec<u32> = (0..8)
            .scan(Pcg32::new(42), |g, _| Some(g.next_u32()))
            .collect();
        let c: Vec<u32> = (0..8)
            .scan(Pcg32::new(43), |g, _| Some(g.next_u32()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        let mut g = Pcg32::new(7);
        let mean = (0..10_000).map(|_| g.unit()).sum::<f64>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }
}
