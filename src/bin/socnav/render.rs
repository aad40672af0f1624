//! `socnav render`: one environment, one episode, drawn frame by frame with `socnav::render`.
//! The batch runs with autoreset DISABLED, so the terminal step's state is still there to draw
//! (with NEXT_STEP the environment would reset on the step after it).

use std::path::Path;

use socnav::render::{self, GifWriter};
use socnav::spec::N_INFO;
use socnav::{Actions, BatchEnv, Config};

use crate::args::RenderArgs;
use crate::outcome::outcome;
use crate::policy::Policy;

/// What to write, from the output file's extension.
enum Output {
    Png,
    Gif,
}

fn output_kind(path: &Path) -> Result<Output, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => Ok(Output::Png),
        Some("gif") => Ok(Output::Gif),
        Some(other) => Err(format!(
            "--out {}: unknown extension `.{other}` (use .gif or .png)",
            path.display()
        )),
        None => Err(format!(
            "--out {}: no extension (use .gif or .png)",
            path.display()
        )),
    }
}

pub fn render(a: &RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let kind = output_kind(&a.out)?;
    let config = Config::from_name_or_path(&a.config)?;
    let size = a.size.unwrap_or(config.render.resolution);
    let frame_ms = config.render.frame_ms;
    let mut env = BatchEnv::single(config, a.seed)?;
    let robot = |env: &BatchEnv| env.state().map(|s| (s.robot_x[0], s.robot_y[0]));
    let mut trail = vec![robot(&env)?];
    let first = render::draw(env.params(), env.state()?, 0, &trail, size)?;
    if let Output::Png = kind {
        render::write_png(&first, &a.out)?;
        println!(
            "socnav render: 1 frame (tick 0, before any step) -> {}",
            a.out.display()
        );
        return Ok(());
    }
    let mut gif = GifWriter::create(&a.out, first.width(), first.height(), frame_ms)?;
    gif.push(&first)?;
    let mut policy = Policy::new(a.policy, a.seed, &env);
    let mut actions = [0.0f32; 3];
    let max_steps = a.steps.unwrap_or(usize::MAX);
    let mut steps = 0;
    let mut ended = false;
    while steps < max_steps && !ended {
        policy.act(&env, &mut actions)?;
        env.step(Actions::Continuous(&actions))?;
        steps += 1;
        trail.push(robot(&env)?);
        gif.push(&render::draw(env.params(), env.state()?, 0, &trail, size)?)?;
        let out = env.outputs();
        ended = out.terminated[0] != 0 || out.truncated[0] != 0;
    }
    let frames = gif.frames();
    gif.finish()?;
    let result = if ended {
        outcome(&env.outputs().info[..N_INFO])
    } else {
        "not finished (stopped by --steps)"
    };
    println!(
        "socnav render: {frames} frames ({steps} steps), outcome: {result} -> {}",
        a.out.display()
    );
    Ok(())
}
