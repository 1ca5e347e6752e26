//! Seeded random scenarios for the optimality comparison.
