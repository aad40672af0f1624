//! The device's element order (`socnav::state::columns::ElementOrder`): the packed state of a
//! rolled-out batch in slot-major order puts element (e, slot) of every slot column at
//! `first word + slot * n_envs + e`, as the shaders' `at_<kind>` computes it from the batch
//! layout's steps, and unpacking it gives back the same state bit for bit.

use socnav::backend::wgsl::{self, BatchLayout};
use socnav::state::BatchState;
use socnav::state::columns::{Elem, ElementOrder};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

/// exp2 after a few steps of turning in place: every slot kind holds entities.
fn rolled_out(n_envs: usize) -> BatchEnv {
    let config = Config::from_name_or_path("exp2").expect("exp2");
    let options = EnvOptions {
        n_envs,
        ..EnvOptions::default()
    };
    let mut env = BatchEnv::new(config, options).expect("batch");
    env.reset(Some(7)).expect("reset");
    let actions: Vec<f32> = (0..n_envs).flat_map(|_| [0.3, 0.0, 0.5]).collect();
    for _ in 0..5 {
        env.step(Actions::Continuous(&actions)).expect("step");
    }
    env
}

/// Contract: every element of every state column sits where the layout's steps say, in both
/// orders, and only the slot columns move.
#[test]
fn packed_elements_sit_where_the_layout_says() {
    let n = 5;
    let env = rolled_out(n);
    let state = env.state().expect("state");
    let columns = state.columns();
    let kinds = wgsl::slot_kinds(&columns);
    assert!(kinds.iter().any(|&(k, _)| k == "human"), "{kinds:?}");
    for order in [ElementOrder::EnvMajor, ElementOrder::SlotMajor] {
        let (mut f, mut u) = (Vec::new(), Vec::new());
        state.pack_in(order, &mut f, &mut u);
        let mut first = [0usize; 2];
        for &(name, elem, cap) in &columns {
            let kind = BatchState::COLUMN_KINDS
                .iter()
                .find(|&&(c, _)| c == name)
                .map(|&(_, k)| k)
                .expect("a declared column");
            let (env_step, slot_step) = if kind == "env" {
                (1, 0)
            } else {
                order.steps(n, cap)
            };
            let host = column_bits(state, name);
            let k = usize::from(elem == Elem::U32);
            for e in 0..n {
                for slot in 0..cap {
                    let at = first[k] + e * env_step + slot * slot_step;
                    let packed = if k == 0 { f[at].to_bits() } else { u[at] };
                    let want = host[e * cap + slot];
                    assert_eq!(packed, want, "{order:?}: {name}[{e}, {slot}] at word {at}");
                }
            }
            first[k] += n * cap;
        }
        assert_eq!(
            first,
            [f.len(), u.len()],
            "{order:?}: every word accounted for"
        );
    }
}

/// Contract: `unpack_in` inverts `pack_in` in both orders, bit for bit.
#[test]
fn unpacking_inverts_packing_in_both_orders() {
    let env = rolled_out(3);
    let state = env.state().expect("state");
    for order in [ElementOrder::EnvMajor, ElementOrder::SlotMajor] {
        let (mut f, mut u) = (Vec::new(), Vec::new());
        state.pack_in(order, &mut f, &mut u);
        let mut back = BatchState::new(state.n_envs, state.strides);
        back.unpack_in(order, &f, &u);
        assert_eq!(
            back.differing_columns(state),
            Vec::<&str>::new(),
            "{order:?}"
        );
    }
}

/// Contract: the batch layout's steps of each slot kind are the device order's, so the
/// shaders' `at_<kind>(e, slot)` finds what `pack_in(DEVICE_ORDER)` put there.
#[test]
fn the_layout_steps_are_the_device_order() {
    let n = 7;
    let env = rolled_out(n);
    let state = env.state().expect("state");
    let columns = state.columns();
    let layout = BatchLayout::new(n, &columns, &env.outputs().columns(), env.layout(), None);
    for (kind, cap) in wgsl::slot_kinds(&columns) {
        let (env_step, slot_step) = wgsl::DEVICE_ORDER.steps(n, cap);
        assert_eq!(
            layout.get(&format!("e_{kind}")),
            Some(env_step as u32),
            "{kind}"
        );
        assert_eq!(
            layout.get(&format!("k_{kind}")),
            Some(slot_step as u32),
            "{kind}"
        );
    }
}

/// Column `name`'s words (an f32's bits), environment-major.
fn column_bits(state: &BatchState, name: &str) -> Vec<u32> {
    let mut copy = state.clone();
    copy.column_words_mut(name).expect("a column").to_vec()
}
