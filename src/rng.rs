//! Counter-based RNG (placeholder, filled in by the rng helper).
