//! Transcendental maths (placeholder, filled in by the math helper).
