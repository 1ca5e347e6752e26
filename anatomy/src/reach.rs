//! Where a needle can go: the region a scenario's cover spends its spheres on.

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The points a needle can pass on its way from the entry to the target: those whose distances
/// to the two add up to at most the needle's length (an ellipsoid with them as foci; RAS, mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// The entry (mm).
    pub entry: [f64; 3],
    /// The target (mm).
    pub target: [f64; 3],
    /// The longest path (mm).
    pub length: f64,
}

impl Reach {
    /// How much the distances from `p` to the entry and the target exceed the length (the
    /// excess falls by at most twice the distance moved).
    fn excess(&self, p: [f64; 3]) -> f64 {
        dist(p, self.entry) + dist(p, self.target) - self.length
    }

    /// Whether a path can pass `p`.
    pub fn holds(&self, p: [f64; 3]) -> bool {
        self.excess(p) <= 0.0
    }

    /// Whether no path can pass any point of the ball about `center` of `radius`.
    pub fn misses(&self, center: [f64; 3], radius: f64) -> bool {
        self.excess(center) > 2.0 * radius
    }
}
