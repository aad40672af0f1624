//! How a finished episode ended, in words, from the info row of its last step (a truncation is
//! a timeout; a wall collision is named apart from other objects).

use socnav::spec::info;

pub fn outcome(row: &[f32]) -> &'static str {
    let on = |k: usize| row[k] != 0.0;
    if on(info::SUCCESS) {
        "success"
    } else if on(info::COLLISION_HUMAN) {
        "collision (human)"
    } else if on(info::COLLISION_WALL) {
        "collision (object: wall)"
    } else if on(info::COLLISION_OBJECT) {
        "collision (object)"
    } else if on(info::OUT_OF_MAP) {
        "out of map"
    } else {
        "timeout"
    }
}
