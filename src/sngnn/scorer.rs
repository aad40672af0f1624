//! The SNGNN-v2 scorer a batch steps with: the network and its edge-weight tables, built once
//! per process for a weight file and a distance range and shared by every thread and batch that
//! use them (the tables are ~90 MB and take about a second and a half to build).

use std::cell::RefCell;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, Weak};

use super::model::{Model, Output, Scratch};
use super::pieces::Tables;
use super::{Graph, load_weights, weights_path};
use crate::SimError;
use crate::config::Config;

/// Distances up to this are always in the tables: the wall-person edges exist below 1.5 m
/// (docs/spec.md 7.3), so their distance never exceeds it.
const WALL_PERSON_RANGE: f32 = 1.5;
/// Head room over the largest room's diagonal, so rounding never sends an edge of the config's
/// rooms to the slow path.
const RANGE_MARGIN: f32 = 1.05;

/// What a batch with the SNGNN-v2 reward needs to score its steps: the shared [`Scorer`] and
/// the packed layout that holds any graph of the config (the GPU backend's graph buffers).
#[derive(Debug, Clone)]
pub struct SngnnReward {
    /// The network and its tables.
    pub scorer: Arc<Scorer>,
    /// [`super::graph::capacity`] of the config.
    pub graphs: super::packed::PackedLayout,
}

impl SngnnReward {
    /// The scorer and graph layout of `config` (whose reward should be SNGNN-v2's).
    ///
    /// # Errors
    /// As [`Scorer::for_config`].
    pub fn for_config(config: &Config) -> Result<Self, SimError> {
        Ok(Self {
            scorer: Scorer::for_config(config)?,
            graphs: super::graph::capacity(config),
        })
    }
}

/// SNGNN-v2 ready to score graphs.
#[derive(Debug)]
pub struct Scorer {
    model: Model,
    tables: Tables,
}

/// Scorers alive in this process, by weight file and table range (bits of the f32).
type Cache = Vec<(PathBuf, u32, Weak<Scorer>)>;
static SCORERS: Mutex<Cache> = Mutex::new(Vec::new());

thread_local! {
    /// Each thread's graph and forward-pass scratch, reused across steps and batches.
    static SCRATCH: RefCell<(Graph, Scratch)> = RefCell::default();
}

impl Scorer {
    /// A scorer from already loaded weights, with tables covering `[0, max_dist]`.
    pub fn new(model: Model, max_dist: f32) -> Self {
        let tables = Tables::new(&model, max_dist);
        Scorer { model, tables }
    }

    /// The scorer for `config`'s weight file and rooms, shared with any other batch of the
    /// process that uses the same.
    ///
    /// # Errors
    /// `SimError::Sngnn` when the weight file is missing (the message says how to install it)
    /// or invalid.
    pub fn for_config(config: &Config) -> Result<Arc<Scorer>, SimError> {
        let path = weights_path(config.reward.sngnn_weights.as_deref()).path;
        let range = table_range(config);
        let mut cache = SCORERS.lock().unwrap_or_else(|e| e.into_inner());
        cache.retain(|(_, _, s)| s.strong_count() > 0);
        if let Some(s) = cache
            .iter()
            .find(|(p, r, _)| *p == path && *r == range.to_bits())
            .and_then(|(_, _, s)| s.upgrade())
        {
            return Ok(s);
        }
        let weights = load_weights(config.reward.sngnn_weights.as_deref())?;
        let scorer = Arc::new(Scorer::new(Model::new(&weights), range));
        cache.push((path, range.to_bits(), Arc::downgrade(&scorer)));
        Ok(scorer)
    }

    /// The network.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The edge-weight tables.
    pub fn tables(&self) -> &Tables {
        &self.tables
    }

    /// The network's output for the room node of `graph`.
    pub fn score(&self, graph: &Graph, s: &mut Scratch) -> Output {
        self.tables.forward(&self.model, graph, s)
    }

    /// Build a graph with `build` into this thread's scratch graph and score it.
    pub fn score_with(&self, build: impl FnOnce(&mut Graph)) -> Output {
        SCRATCH.with_borrow_mut(|(graph, scratch)| {
            build(graph);
            self.score(graph, scratch)
        })
    }
}

/// The distance range of the tables for `config`: every distance feature is a distance
/// between two points of a room (in units of 10 m, docs/spec.md 7.3) or a wall-person distance
/// below 1.5 m, so the diagonal of a square as large as the config's largest room side bounds it
/// (whatever the room's shape).
pub fn table_range(config: &Config) -> f32 {
    let side = config.room.size_x[1].max(config.room.size_y[1]).max(1) as f32;
    let diagonal_in_10_m = side * std::f32::consts::SQRT_2 / 10.0;
    diagonal_in_10_m.max(WALL_PERSON_RANGE) * RANGE_MARGIN
}
