//! The floor of every curvature factor the world draws (the needle's, a segment's, a layer's).

/// The smallest curvature factor a draw may give (a wild spread cannot flip the bevel).
pub const MIN_FACTOR: f32 = 0.2;
