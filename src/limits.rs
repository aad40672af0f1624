//! Fixed bounds of one environment that the step's stack arrays and scratch are sized by and that
//! config validation enforces (`config::validate`): a leaf module, so that validation reads them
//! without depending on the stages that use them.

/// Most members a group may have: group layouts live in stack arrays (`scenario::place`,
/// formation and events).
pub const MAX_GROUP: usize = 64;

/// Most slots of one kind a permutation can reorder (humans, groups, laptops, laptop users of
/// one environment: `state::columns`, the social events and `systems::regroup`).
pub const MAX_PERMUTE: usize = 256;

/// Most ORCA obstacle polygons of one environment (`systems::orca_obstacles`).
pub const MAX_POLYGONS: usize = 256;
