//! ORCA solver (placeholder, filled in by the orca helper).
