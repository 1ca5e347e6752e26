//! The one seeded generator, defined in `needle-sim` (the simulated tissue and tracker draw from
//! it too) and re-exported here for the analysis and the tests.

pub use needle_sim::random::*;
