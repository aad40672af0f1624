//! `socnav heatmap`: the SocNavGym paper's figure of discomfort around people for one scene,
//! SNGNN-v2 beside DSRNN (`socnav::heatmap` computes the fields, `socnav::render::heatmap`
//! draws them). Inputs are checked before the weights are loaded, so a bad argument fails fast.

use std::time::Instant;

use socnav::Config;
use socnav::heatmap::{self, Scene, cell};
use socnav::render::{self, heatmap::Figure};
use socnav::sngnn::Scorer;

use crate::args::HeatmapArgs;

pub fn heatmap(a: &HeatmapArgs) -> Result<(), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let is_png = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(format!(
            "--out {}: the heatmap is written as PNG (use .png)",
            a.out.display()
        )
        .into());
    }
    // What the arguments can get wrong is refused before the weights load and the placements run.
    heatmap::check_grid(a.grid)?;
    if let Some(heading) = a.heading {
        heatmap::check_heading(heading)?;
    }
    socnav::render::check_size("heatmap figure", "panel size", a.size)
        .map_err(|e| format!("--size {}: {e}", a.size))?;
    let config = Config::from_name_or_path(&a.config)?;
    heatmap::require_sngnn(&config, &a.config)?;
    let scorer = Scorer::for_config(&config)?;
    eprintln!(
        "socnav heatmap: SNGNN-v2 ready ({:.1} s)",
        start.elapsed().as_secs_f64()
    );
    let scene = Scene::new(&config, a.seed)?;
    let heading = a.heading.unwrap_or_else(|| scene.robot_heading());
    let total = a.grid * a.grid;
    let every = (total / 10).max(1);
    eprintln!(
        "socnav heatmap: {total} placements ({}x{}) of {} seed {}, heading {heading:.3} rad",
        a.grid, a.grid, a.config, a.seed
    );
    let progress = |done: usize| {
        if done.is_multiple_of(every) || done == total {
            eprintln!(
                "  {done}/{total} placements ({:.1} s)",
                start.elapsed().as_secs_f64()
            );
        }
    };
    let h = scene.heatmap(a.grid, heading, Some(&scorer), &progress)?;
    // A config file is named by its stem, so that a long path does not crowd the title.
    let path = std::path::Path::new(&a.config);
    let name = match path.extension() {
        Some(_) => path
            .file_stem()
            .map_or(a.config.clone(), |s| s.to_string_lossy().into_owned()),
        None => a.config.clone(),
    };
    let caption = format!(
        "{name} seed {}, {}x{}, heading {heading:.2} rad, robot at rest",
        a.seed, a.grid, a.grid
    );
    let figure = Figure {
        heatmap: &h,
        params: scene.params(),
        state: scene.state(),
        caption: &caption,
        panel_px: a.size,
    };
    let image = render::heatmap::draw(&figure)?;
    render::write_png(&image, &a.out)?;
    let scored = h.mask.iter().filter(|&&m| m == cell::FREE).count();
    let range = |v: &[f32]| {
        let it = || v.iter().copied().filter(|x| !x.is_nan());
        (
            it().fold(f32::INFINITY, f32::min),
            it().fold(f32::NEG_INFINITY, f32::max),
        )
    };
    let (smin, smax) = range(&h.sngnn);
    let (dmin, dmax) = range(&h.dsrnn);
    println!(
        "socnav heatmap: {scored} of {total} placements scored; SNGNN-v2 q1 {smin:.3}..{smax:.3}, \
         DSRNN term {dmin:.3}..{dmax:.3}; {}x{} px -> {} ({:.1} s)",
        image.width(),
        image.height(),
        a.out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
