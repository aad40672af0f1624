//! Golden replay against SocNavGym 0.1.1 (docs/spec.md, fidelity; golden README section 8).
//!
//! For every recorded episode: load the reference state before each step into socnav through
//! `set_state`, take the recorded action, and compare everything the step returns (observation,
//! reward, terminated/truncated, every info key) and the state it leaves (robot, shadow robot,
//! humans, groups, metric accumulators, reward memory) with the recording.
//!
//! Environment: `SOCNAV_GOLDEN_DIR` (default `tests/data/golden/socnavgym`), `SOCNAV_GOLDEN_FILTER`
//! (file-name prefix). Unfiltered, every episode whose config this build replays is run and the
//! others are skipped with the reason printed.
//!
//! Where 0.1.1 has a bug that socnav fixes (docs/fidelity.md), that field is compared with the
//! corrected value, computed here from the recorded state; the test also checks that the same
//! computation with the bug reproduces the recording, so the correction is the only difference.
//! Decisions within a documented epsilon of their threshold may flip; flips are counted and
//! printed, and the test fails if there are too many or if anything else differs.

mod common;
mod golden;

use golden::{Report, golden_dir_or_skip, load_episodes, replay_episode};
use socnav::config::ContactShape;

/// Configs this build replays; the SNGNN-v2 ones need the weight file (skipped loudly without
/// it unless `REQUIRE_SNGNN=1`).
const REPLAYABLE: [&str; 7] = [
    "exp1_no_sngnn",
    "exp2_no_sngnn",
    "exp3_no_sngnn",
    "lroom_mixed",
    "corridor_mixed",
    "exp1_with_sngnn",
    "exp2_with_sngnn",
];

#[test]
fn golden_replay() {
    let Some(dir) = golden_dir_or_skip("golden_replay") else {
        return;
    };
    let filter = std::env::var("SOCNAV_GOLDEN_FILTER").ok();
    let episodes = load_episodes(&dir, filter.as_deref());
    assert!(
        !episodes.is_empty(),
        "no golden episodes in {} (filter {filter:?})",
        dir.display()
    );
    // Every episode twice: with socnav's default exact discs (contacts within the 64-gon's inset
    // counted apart, docs/fidelity.md) and with 0.1.1's 64-gons (`contact_shape = "polygon64"`),
    // where those contacts must be decided as 0.1.1 decided them.
    let mut totals = Vec::new();
    for shape in [ContactShape::Exact, ContactShape::Polygon64] {
        let mut total = Report::default();
        let mut replayed = 0;
        for (name, ep) in &episodes {
            let config_name = ep.config_name();
            if !REPLAYABLE.contains(&config_name.as_str()) {
                println!("SKIP {name}: config `{config_name}` is not one this build replays");
                continue;
            }
            if config_name.ends_with("_with_sngnn") && common::sngnn::real_weights().is_none() {
                continue;
            }
            let report = replay_episode(name, ep, shape);
            println!("{name} ({shape:?} contacts): {}", report.summary());
            total.merge(&report);
            replayed += 1;
        }
        println!(
            "TOTAL over {replayed} episodes ({shape:?} contacts): {}",
            total.summary()
        );
        assert!(
            replayed > 0,
            "no replayable episode matched the filter {filter:?}"
        );
        totals.push(total);
    }
    for total in &totals {
        total.assert_ok();
    }
}
