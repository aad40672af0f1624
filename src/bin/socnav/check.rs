//! `socnav check-config`: validate a config, then print it with every default resolved and the
//! batch layout it implies.

use socnav::Config;
use socnav::spec::{ENTITY_KEYS, INTERACTION_KEYS, ObsLayout};
use socnav::state::Caps;

use crate::args::CheckArgs;

pub fn check(a: &CheckArgs) -> Result<(), Box<dyn std::error::Error>> {
    let config = Config::from_name_or_path(&a.config)?;
    let caps = Caps::from_config(&config);
    let layout = ObsLayout::new(&caps, &config.observation);
    println!("# {}: valid. Resolved configuration:\n", a.config);
    println!("{}", config.to_toml_string());
    println!("# Capacities per environment: {caps:?}");
    let per_type: Vec<String> = ENTITY_KEYS
        .iter()
        .zip(layout.capacity)
        .map(|(k, n)| format!("{k} {n}"))
        .collect();
    println!(
        "# Observation: {} floats per environment (robot {}, records of 14 floats: {})",
        layout.dim,
        layout.robot,
        per_type.join(", ")
    );
    let pairs: Vec<String> = INTERACTION_KEYS
        .iter()
        .zip(layout.pairs)
        .map(|(k, n)| format!("{k} {n}"))
        .collect();
    println!("# Interaction pairs at most: {}", pairs.join(", "));
    Ok(())
}
