// requires: common/rng.wgsl
//
// Twin of the parts of src/scenario/place.rs that the step uses (the rest of scenario generation
// stays on the host): the sampling box, group layouts, headings and laptop seats. Library file
// (no entry point, reads `params`). Same operations in the same order as the Rust file; change
// both in the same commit. A pose is a vec3<f32> (x m, y m, heading rad).
//
// Group layouts fill arrays of place_group_cap() poses, the capacity of a forming crowd's slots
// (`group_size`'s maximum): every group the step lays out (a crowd forming or formed) has at most
// that many members (Rust's bound is PLACE_MAX_GROUP, which validation keeps above it); members
// beyond it are not laid out.

// Size of the member arrays: a compile-time size class (backend::wgsl::SizeClasses), at least
// the batch's capacity `place_group_cap`, which counts are compared with.
const PLACE_GROUP_ARRAY: u32 = ARRAY_CROWD_MEMBERS;

// Members of one forming crowd (at least 1).
fn place_group_cap() -> u32 {
    return max(batch.s_cf_human, 1u);
}

// Rust `SamplingBox::new`: half extents of the box [-X/2 + margin, X/2 - margin] ×
// [-Y/2 + margin, Y/2 - margin] of an x by y room (m).
fn place_sampling_box(x: f32, y: f32) -> vec2<f32> {
    return vec2<f32>(0.5 * x - params.margin, 0.5 * y - params.margin);
}

// Rust `SamplingBox::point`: a uniform point of the box with half extents `h`.
fn place_box_point(h: vec2<f32>, rng: ptr<function, RngStream>) -> vec2<f32> {
    let x = rng_uniform(rng, -h.x, h.x);
    let y = rng_uniform(rng, -h.y, h.y);
    return vec2<f32>(x, y);
}

// Rust `heading`: a uniform heading in [-π, π).
fn place_heading(rng: ptr<function, RngStream>) -> f32 {
    return rng_uniform(rng, -MATH_PI, MATH_PI);
}

// Rust `group_layout`: the poses of the n (<= place_group_cap()) members of a group around
// (cx, cy) into out[0..n].
fn place_group_layout(
    rng: ptr<function, RngStream>,
    cx: f32,
    cy: f32,
    n: u32,
    standing: bool,
    out: ptr<function, array<vec3<f32>, PLACE_GROUP_ARRAY>>,
) {
    let jitter = MATH_PI / 14.0;
    let shared_theta = place_heading(rng);
    for (var k = 0u; k < min(n, place_group_cap()); k++) {
        let phi = math_wrap_angle(2.0 * MATH_PI * f32(k) / f32(n));
        let d1 = rng_uniform(rng, -jitter, jitter);
        let d2 = rng_uniform(rng, -jitter, jitter);
        let x = cx + params.group_radius * math_cos(phi + d1);
        let y = cy + params.group_radius * math_sin(phi + d2);
        var theta = shared_theta;
        if (standing) {
            theta = phi - MATH_PI + rng_uniform(rng, -jitter, jitter);
        }
        (*out)[k] = vec3<f32>(x, y, theta);
    }
}

// Rust `seat`: the seat pose of the user of the laptop at (lx, ly) with heading `ltheta`.
fn place_seat(lx: f32, ly: f32, ltheta: f32) -> vec3<f32> {
    let d = params.laptop_width + params.human_laptop_distance;
    let sc = math_sin_cos(ltheta);
    return vec3<f32>(lx + d * sc.x, ly - d * sc.y, ltheta + 0.5 * MATH_PI);
}
