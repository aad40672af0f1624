//! Stage `group_motion` (docs/spec.md 4.4): the members of a moving group walk with the group's
//! ORCA velocity, divided by the member count as in 0.1.1 (`model.group_velocity_divided`), plus
//! Gaussian noise of standard deviation `group.velocity_noise_std` per member and axis, drawn
//! every step. The stored centre then becomes the members' centroid. Standing groups never move.

use crate::math;
use crate::params::StepParams;
use crate::state::group_kind;

use super::Batch;

/// RNG stream kind of the group velocity noise (`sub` = tick).
pub const STREAM_GROUP_NOISE: u32 = 4;

/// Move the members of every moving group of environment `e`.
pub fn group_motion(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    let s = &mut b.s;
    let mut rng = super::LazyStream::new(s, e, STREAM_GROUP_NOISE);
    let hb = e * s.strides.humans;
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        if s.g_kind[g] != group_kind::MOVING {
            continue;
        }
        let n = s.g_count[g];
        let scale = if p.group_velocity_divided != 0 {
            1.0 / n as f32
        } else {
            1.0
        };
        let (gvx, gvy) = (s.g_vx[g] * scale, s.g_vy[g] * scale);
        let first = hb + s.g_first[g] as usize;
        let (mut cx, mut cy) = (0.0f32, 0.0f32);
        for i in first..first + n as usize {
            // Without noise there is nothing to draw (0.1.1 draws zeros; the counter-based streams
            // of later draws do not depend on it).
            let (nx, ny) = if p.replay != 0 {
                (s.h_noise_x[i], s.h_noise_y[i])
            } else if p.group_noise_std > 0.0 {
                (
                    p.group_noise_std * rng.get().normal(),
                    p.group_noise_std * rng.get().normal(),
                )
            } else {
                (0.0, 0.0)
            };
            let vx = gvx + nx;
            let vy = gvy + ny;
            let speed = (vx * vx + vy * vy).sqrt();
            let theta = math::atan2(vy, vx);
            let (sn, c) = math::sin_cos(theta);
            s.h_speed[i] = speed;
            s.h_theta[i] = theta;
            s.h_vx[i] = speed * c;
            s.h_vy[i] = speed * sn;
            s.h_x[i] += speed * p.dt * c;
            s.h_y[i] += speed * p.dt * sn;
            cx += s.h_x[i];
            cy += s.h_y[i];
        }
        s.g_x[g] = cx / n as f32;
        s.g_y[g] = cy / n as f32;
    }
}
