//! `fused.cu`'s kernel in Rust, operation for operation: the CPU's evaluation of the fused
//! objective, bit for bit what the GPU computes (the transcendental functions are
//! [`super::portable`]'s, the kernel's `pg_*`; additions, products, divisions and square roots
//! are IEEE on both, and neither contracts a product and a sum into one rounding). Each sample
//! is one call, so a batch is evaluated in parallel with the same bits on any number of threads.
//! The tests hold it to a C++ build of `fused.cu` bit for bit, and to the candle graph.

use super::fused::Inputs;
use super::portable;

type V3 = [f64; 3];

fn dot3(a: &[f64], b: &[f64]) -> f64 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

fn beyond(x: f64, dead_zone: f64) -> f64 {
    if x > dead_zone {
        x
    } else {
        0.0
    }
}

fn cross(a: &[f64], b: &[f64]) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `fused.cu`'s `closest_parameters`: `frames::closest_parameters_of_segments`, whose operations
/// the kernel's copy repeats in order (the tests hold the two to the bit).
fn closest_parameters(p1: &[f64], q1: &[f64], p2: &[f64], q2: &[f64]) -> (f64, f64) {
    let v = |p: &[f64]| nalgebra::Vector3::new(p[0], p[1], p[2]);
    crate::frames::closest_parameters_of_segments(v(p1), v(q1), v(p2), v(q2))
}

/// The link frames of one sample: row-major rotations and origins, 0 the base.
struct Links {
    rot: Vec<[f64; 9]>,
    org: Vec<V3>,
}

/// The gradient rows of one sample.
struct Grad<'a> {
    q: &'a mut [f64],
    d: &'a mut [f64],
    a: &'a mut [f64],
}

impl Grad<'_> {
    /// `fused.cu`'s `add_end`.
    fn add_end(&mut self, w: &V3, link: usize, kind: i32, end: usize, point: &[f64], links: &Links) {
        for j in 1..=link {
            let r = &links.rot[j];
            let z = [r[2], r[5], r[8]];
            let v = [point[0] - links.org[j][0], point[1] - links.org[j][1], point[2] - links.org[j][2]];
            self.q[j - 1] += dot3(w, &cross(&z, &v));
        }
        for m in 1..link {
            let r = &links.rot[m];
            self.d[m - 1] += dot3(w, &[r[2], r[5], r[8]]);
            self.a[m - 1] += dot3(w, &[r[0], r[3], r[6]]);
        }
        let r = &links.rot[link];
        let (z, x) = ([r[2], r[5], r[8]], [r[0], r[3], r[6]]);
        if kind == 0 && end == 1 {
            self.d[link - 1] += dot3(w, &z);
        } else if kind == 1 {
            self.d[link - 1] += dot3(w, &z);
            if end == 1 {
                self.a[link - 1] += dot3(w, &x);
            }
        }
    }
}

/// Sample `b` into `o` (`2 + 3 n` values: distance, collision, the gradient rows), as one GPU
/// thread computes it.
pub(super) fn sample(inp: &Inputs, b: usize, o: &mut [f64]) {
    let n = inp.scalars[1] as usize;
    let k = &inp.constants;
    let design = inp.sample_design[b] as usize;
    let qs = &inp.q[b * n..(b + 1) * n];
    let dr = &inp.d[design * n..(design + 1) * n];
    let ar = &inp.a[design * n..(design + 1) * n];
    let ds = &inp.design_static[design * (2 * n + 24)..(design + 1) * (2 * n + 24)];
    let (cos_alpha, sin_alpha) = (&ds[..n], &ds[n..2 * n]);
    let base = &ds[2 * n..2 * n + 12];
    let tool = &ds[2 * n + 12..2 * n + 24];
    o.iter_mut().for_each(|v| *v = 0.0);
    let (head, grads) = o.split_at_mut(2);
    let (gq, rest) = grads.split_at_mut(n);
    let (gd, ga) = rest.split_at_mut(n);
    let mut g = Grad { q: gq, d: gd, a: ga };

    // Link frames, as fused.cu computes them.
    let mut links = Links {
        rot: Vec::with_capacity(n + 1),
        org: Vec::with_capacity(n + 1),
    };
    let (mut fx, mut fy, mut fz) = (
        [base[0], base[3], base[6]],
        [base[1], base[4], base[7]],
        [base[2], base[5], base[8]],
    );
    let mut fo = [base[9], base[10], base[11]];
    links.rot.push(std::array::from_fn(|i| base[i]));
    links.org.push(fo);
    for j in 0..n {
        if j > 0 {
            for i in 0..3 {
                fo[i] = (fo[i] + fx[i] * ar[j - 1]) + fz[i] * dr[j - 1];
            }
            let (c, s) = (cos_alpha[j - 1], sin_alpha[j - 1]);
            for i in 0..3 {
                let y = fy[i] * c + fz[i] * s;
                let z = fz[i] * c - fy[i] * s;
                fy[i] = y;
                fz[i] = z;
            }
        }
        let (c, s) = (portable::cos(qs[j]), portable::sin(qs[j]));
        for i in 0..3 {
            let x = fx[i] * c + fy[i] * s;
            let y = fy[i] * c - fx[i] * s;
            fx[i] = x;
            fy[i] = y;
        }
        let mut rot = [0.0; 9];
        for i in 0..3 {
            rot[3 * i] = fx[i];
            rot[3 * i + 1] = fy[i];
            rot[3 * i + 2] = fz[i];
        }
        links.rot.push(rot);
        links.org.push(fo);
    }
    let mut last = [0.0; 3];
    let mut tool_rot = [0.0; 9];
    let mut tool_pos = [0.0; 3];
    for i in 0..3 {
        last[i] = (fo[i] + fx[i] * ar[n - 1]) + fz[i] * dr[n - 1];
    }
    for i in 0..3 {
        let row = [fx[i], fy[i], fz[i]];
        for c in 0..3 {
            tool_rot[3 * i + c] = (row[0] * tool[c] + row[1] * tool[3 + c]) + row[2] * tool[6 + c];
        }
        tool_pos[i] = last[i] + ((row[0] * tool[9] + row[1] * tool[10]) + row[2] * tool[11]);
    }

    // Pose distance.
    let goal = &inp.goal_static[inp.sample_goal[b] as usize * 13..][..13];
    let error = [tool_pos[0] - goal[0], tool_pos[1] - goal[1], tool_pos[2] - goal[2]];
    let error_norm = (dot3(&error, &error) + k.sqrt_floor).sqrt();
    let position = beyond(error_norm, k.dead_zone);
    if position > 0.0 {
        let w: V3 = std::array::from_fn(|i| k.distance_weight * error[i] / error_norm);
        for j in 1..=n {
            let r = &links.rot[j];
            let z = [r[2], r[5], r[8]];
            let v = [
                tool_pos[0] - links.org[j][0],
                tool_pos[1] - links.org[j][1],
                tool_pos[2] - links.org[j][2],
            ];
            let x = [r[0], r[3], r[6]];
            g.q[j - 1] += dot3(&w, &cross(&z, &v));
            g.d[j - 1] += dot3(&w, &z);
            g.a[j - 1] += dot3(&w, &x);
        }
    }
    let gr = &goal[3..12];
    let mut rotation = 0.0;
    let mut turn = [0.0; 3];
    match goal[12] as i32 {
        0 => {
            let mut m = [0.0; 9];
            for i in 0..3 {
                for c in 0..3 {
                    m[3 * i + c] = (gr[i] * tool_rot[c] + gr[3 + i] * tool_rot[3 + c]) + gr[6 + i] * tool_rot[6 + c];
                }
            }
            let trace = (m[0] + m[4]) + m[8];
            let v = [m[7] - m[5], m[2] - m[6], m[3] - m[1]];
            let length = (dot3(&v, &v) + k.sqrt_floor).sqrt();
            let angle = beyond(portable::atan2(length * 0.5, (trace - 1.0) * 0.5), k.dead_zone);
            rotation = angle;
            if angle > 0.0 {
                for i in 0..3 {
                    turn[i] = ((gr[3 * i] * v[0] + gr[3 * i + 1] * v[1]) + gr[3 * i + 2] * v[2]) / length;
                }
            }
        }
        1 => {
            let tz = [tool_rot[2], tool_rot[5], tool_rot[8]];
            let gz = [gr[2], gr[5], gr[8]];
            rotation = (1.0 - dot3(&gz, &tz)) * 0.5;
            let c = cross(&tz, &gz);
            for i in 0..3 {
                turn[i] = -0.5 * c[i];
            }
        }
        _ => {}
    }
    let rotation_scale = k.distance_weight * k.rotation_weight;
    for j in 1..=n {
        let r = &links.rot[j];
        g.q[j - 1] += rotation_scale * dot3(&turn, &[r[2], r[5], r[8]]);
    }
    head[0] = position + rotation * k.rotation_weight;

    // Capsule ends.
    let capsule_count = inp.scalars[2] as usize;
    let mut ends = vec![[0.0; 6]; capsule_count];
    for (c, slot) in ends.iter_mut().enumerate() {
        let link = inp.capsule_link[c] as usize;
        let r = &links.rot[link];
        let zd: V3 = std::array::from_fn(|i| r[3 * i + 2] * dr[link - 1]);
        let xa: V3 = std::array::from_fn(|i| r[3 * i] * ar[link - 1]);
        for i in 0..3 {
            let (start, end) = match inp.capsule_kind[c] {
                0 => (links.org[link][i], links.org[link][i] + zd[i]),
                1 => {
                    let start = links.org[link][i] + zd[i];
                    (start, start + xa[i])
                }
                _ => (links.org[link][i], links.org[link][i]),
            };
            slot[i] = start;
            slot[3 + i] = end;
        }
    }

    // Centres and half lengths: far pairs are skipped, as in the kernel.
    let mid: Vec<[f64; 4]> = ends
        .iter()
        .map(|e| {
            let axis = [e[3] - e[0], e[4] - e[1], e[5] - e[2]];
            [
                (e[0] + e[3]) * 0.5,
                (e[1] + e[4]) * 0.5,
                (e[2] + e[5]) * 0.5,
                dot3(&axis, &axis).sqrt() * 0.5,
            ]
        })
        .collect();
    let far_margin = 1e-9;

    // Each pair's closest candidate, its cost and gradient.
    let e1 = portable::exp(-1.0);
    let scale = 1.0 / (1.0 - e1);
    let mut collision = 0.0;
    let (candidate_count, pair_count, shape_count) = (inp.scalars[3] as usize, inp.scalars[4], inp.scalars[5] as usize);
    let mut next = 0;
    for pair in 0..pair_count {
        let mut last = next;
        while last < candidate_count && inp.candidate_int[4 * last] == pair {
            last += 1;
        }
        let far = (next..last).all(|c| {
            let ci = &inp.candidate_int[4 * c..4 * c + 4];
            let cr = &inp.candidate_real[11 * c..11 * c + 11];
            if ci[2] > 1 {
                return false;
            }
            let m1 = &mid[ci[1] as usize];
            let m2: &[f64] = if ci[2] == 0 { &mid[ci[3] as usize] } else { &cr[7..11] };
            let apart = [m1[0] - m2[0], m1[1] - m2[1], m1[2] - m2[2]];
            let reach = (((k.threshold + far_margin) + m1[3]) + m2[3]) + cr[6];
            dot3(&apart, &apart) >= reach * reach
        });
        if far {
            next = last;
            continue;
        }
        let mut best: Option<usize> = None;
        let (mut best_gap, mut best_s, mut best_t) = (0.0, 0.0, 0.0);
        let mut best_normal = [0.0; 3];
        let mut best_has_normal = false;
        while next < candidate_count && inp.candidate_int[4 * next] == pair {
            let ci = &inp.candidate_int[4 * next..4 * next + 4];
            let cr = &inp.candidate_real[11 * next..11 * next + 11];
            let (p1, q1) = (&ends[ci[1] as usize][..3], &ends[ci[1] as usize][3..]);
            let (mut s, mut t, mut normal, mut has_normal) = (0.0, 0.0, [0.0; 3], false);
            let gap = match ci[2] {
                2 => (p1[2].min(q1[2]) - cr[6]) - cr[0],
                3 => {
                    let w = &inp.witness[(b * shape_count + ci[3] as usize) * 8..][..8];
                    let mut offset = [0.0; 3];
                    for i in 0..3 {
                        let point = p1[i] + (q1[i] - p1[i]) * w[1];
                        offset[i] = point - w[5 + i];
                    }
                    s = w[1];
                    normal = [w[2], w[3], w[4]];
                    has_normal = true;
                    w[0] - dot3(&w[2..5], &offset)
                }
                kind => {
                    let (p2, q2) = if kind == 0 {
                        (&ends[ci[3] as usize][..3], &ends[ci[3] as usize][3..])
                    } else {
                        (&cr[..3], &cr[3..6])
                    };
                    (s, t) = closest_parameters(p1, q1, p2, q2);
                    let between: V3 = std::array::from_fn(|i| (p2[i] + (q2[i] - p2[i]) * t) - (p1[i] + (q1[i] - p1[i]) * s));
                    let distance = dot3(&between, &between).sqrt();
                    if distance >= k.meet {
                        normal = std::array::from_fn(|i| between[i] / distance);
                        has_normal = true;
                    }
                    distance - cr[6]
                }
            };
            if best.is_none() || gap < best_gap {
                best = Some(next);
                (best_gap, best_s, best_t, best_has_normal, best_normal) = (gap, s, t, has_normal, normal);
            }
            next += 1;
        }
        let Some(best) = best else { continue };
        let exp_gap = portable::exp(best_gap * (-1.0 / k.threshold));
        let cost = exp_gap - e1;
        if cost.is_nan() || cost <= 0.0 {
            continue;
        }
        collision += cost;
        let slope = k.collision_weight * scale * exp_gap * (-1.0 / k.threshold);
        let ci = &inp.candidate_int[4 * best..4 * best + 4];
        let capsule = ci[1] as usize;
        let (link, kind) = (inp.capsule_link[capsule] as usize, inp.capsule_kind[capsule]);
        if ci[2] == 2 {
            let lower = usize::from(ends[capsule][5] < ends[capsule][2]);
            g.add_end(
                &[0.0, 0.0, slope],
                link,
                kind,
                lower,
                &ends[capsule][3 * lower..3 * lower + 3],
                &links,
            );
            continue;
        }
        if !best_has_normal {
            continue;
        }
        let w: V3 = std::array::from_fn(|i| -slope * (1.0 - best_s) * best_normal[i]);
        g.add_end(&w, link, kind, 0, &ends[capsule][..3], &links);
        let w: V3 = std::array::from_fn(|i| -slope * best_s * best_normal[i]);
        g.add_end(&w, link, kind, 1, &ends[capsule][3..], &links);
        if ci[2] == 0 {
            let other = ci[3] as usize;
            let (link_b, kind_b) = (inp.capsule_link[other] as usize, inp.capsule_kind[other]);
            let w: V3 = std::array::from_fn(|i| slope * (1.0 - best_t) * best_normal[i]);
            g.add_end(&w, link_b, kind_b, 0, &ends[other][..3], &links);
            let w: V3 = std::array::from_fn(|i| slope * best_t * best_normal[i]);
            g.add_end(&w, link_b, kind_b, 1, &ends[other][3..], &links);
        }
    }
    head[1] = collision * scale;
}
