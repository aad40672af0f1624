//! SNGNN-v2 batches rolled out on the CPU without `BatchEnv` (which would need the weights):
//! every stage of the step with the DSRNN reward, and where the SNGNN-v2 reward would score (a
//! stepping environment whose step is not terminal) the frame recorded and the graph built and
//! packed, as the stages `sngnn_graph` and `sngnn_score` do before the network runs. The step is split at that point so
//! that a device pass can start from the same state.

use socnav::outputs::Outputs;
use socnav::pipeline::{Batch, STAGES};
use socnav::rng::RngStream;
use socnav::sngnn::packed::PackedLayout;
use socnav::sngnn::{Graph, RELATIONS, frame, graph};
use socnav::spec::{N_INFO, ObsLayout, info};
use socnav::state::{BatchState, Caps};
use socnav::{AutoresetMode, Config, StepParams};

/// A batch of an SNGNN config, its packed graphs, and the scratch graph.
pub struct SngnnRollout {
    /// The config's parameters (SNGNN-v2 reward; the stages run with the DSRNN one).
    pub p: StepParams,
    pub s: BatchState,
    pub o: Outputs,
    /// `graph::capacity` of the config.
    pub graphs: PackedLayout,
    /// Every environment's packed graph (u32 regions), as the last scoring left them.
    pub packed_u32: Vec<u32>,
    /// Every environment's packed graph (f32 regions).
    pub packed_f32: Vec<f32>,
    /// Largest graph built so far: nodes, edges, frames.
    pub largest: (usize, usize, usize),
    /// Edges built so far, per relation.
    pub relations: [usize; RELATIONS],
    graph: Graph,
}

impl SngnnRollout {
    /// `n_envs` environments of `config` (whose reward must be SNGNN-v2), each reset.
    pub fn new(config: &Config, n_envs: usize, seed: u64) -> Self {
        let caps = Caps::from_config(config);
        assert!(caps.frames > 0, "the config's reward is not SNGNN-v2");
        let p = StepParams::new(config, AutoresetMode::NextStep);
        let graphs = graph::capacity(config);
        let mut this = Self {
            p,
            s: BatchState::seeded(n_envs, caps, seed),
            o: Outputs::new(n_envs, ObsLayout::new(&caps, &config.observation)),
            packed_u32: vec![0; n_envs * graphs.u32_stride()],
            packed_f32: vec![0.0; n_envs * graphs.f32_stride()],
            graphs,
            largest: (0, 0, 0),
            relations: [0; RELATIONS],
            graph: Graph::default(),
        };
        let mut b = this.batch(&[]);
        for e in 0..n_envs {
            socnav::systems::reset::reset_and_observe(&p, &mut b, e);
        }
        assert!(b.error.is_none(), "reset: {:?}", b.error);
        this
    }

    fn batch<'a>(&'a mut self, actions: &'a [f32]) -> Batch<'a> {
        Batch {
            s: self.s.chunk(),
            o: self.o.chunk(),
            actions,
            sngnn: None,
            error: None,
        }
    }

    /// Run the stages `which` selects over every environment, in step order, with the DSRNN
    /// reward (no network).
    fn run(&mut self, actions: &[f32], which: impl Fn(usize) -> bool) {
        let mut dsrnn = self.p;
        dsrnn.reward_kind = 0;
        let n = self.s.n_envs;
        let mut b = self.batch(actions);
        for (k, stage) in STAGES.iter().enumerate() {
            if which(k) {
                for e in 0..n {
                    (stage.run)(&dsrnn, &mut b, e);
                }
            }
        }
        assert!(b.error.is_none(), "step: {:?}", b.error);
    }

    fn reward_index() -> usize {
        STAGES
            .iter()
            .position(|s| s.name == "reward")
            .expect("a reward stage")
    }

    /// Uniform actions in [-1.5, 1.5] (the stages clip) from `rng`, the lateral one 0 unless the
    /// robot is holonomic (as `common::gpu::random_actions`).
    pub fn random_actions(&self, rng: &mut RngStream) -> Vec<f32> {
        let holonomic = self.p.holonomic != 0;
        (0..3 * self.s.n_envs)
            .map(|k| {
                let a = 3.0 * rng.next_f32() - 1.5;
                if k % 3 == 1 && !holonomic { 0.0 } else { a }
            })
            .collect()
    }

    /// The stages of a step up to and including the reward.
    pub fn step_to_reward(&mut self, actions: &[f32]) {
        let r = Self::reward_index();
        self.run(actions, |k| k <= r);
    }

    /// The stages after the reward.
    pub fn finish_step(&mut self, actions: &[f32]) {
        let r = Self::reward_index();
        self.run(actions, |k| k > r);
    }

    /// Whether the SNGNN-v2 reward scores environment `e` this step: it steps and no outcome
    /// flag was raised (the reward stage's condition).
    pub fn scores(&self, e: usize) -> bool {
        let flag = |k: usize| self.o.info[e * N_INFO + k] != 0.0;
        self.s.stepping[e] != 0
            && !flag(info::OUT_OF_MAP)
            && !flag(info::SUCCESS)
            && !flag(info::COLLISION)
            && !flag(info::TIMEOUT)
    }

    /// What the SNGNN-v2 stages do before the network, for every environment the reward scores:
    /// record the frame, build the graph, pack it; every other environment's packed graph gets
    /// no nodes, as the device's `sngnn_graph` pass does so that its network skips them.
    /// Returns how many environments scored.
    pub fn score(&mut self) -> usize {
        let (us, fs) = (self.graphs.u32_stride(), self.graphs.f32_stride());
        let mut scored = 0;
        for e in 0..self.s.n_envs {
            if !self.scores(e) {
                self.packed_u32[e * us + socnav::sngnn::packed::words::NODES] = 0;
                continue;
            }
            scored += 1;
            let mut chunk = self.s.chunk();
            frame::record(&self.p, &mut chunk, e);
            let frames = graph::build(&self.p, &chunk, e, &mut self.graph);
            let g = &self.graph;
            for &r in &g.rel {
                self.relations[usize::from(r)] += 1;
            }
            self.largest = (
                self.largest.0.max(g.nodes),
                self.largest.1.max(g.src.len()),
                self.largest.2.max(frames),
            );
            self.graphs
                .pack(
                    g,
                    &mut self.packed_u32[e * us..(e + 1) * us],
                    &mut self.packed_f32[e * fs..(e + 1) * fs],
                )
                .unwrap_or_else(|err| panic!("environment {e}: {err}"));
        }
        scored
    }
}
