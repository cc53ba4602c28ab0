//! Quasi-static liquid (the paper's appendix): the liquid surface is a plane `n·x = d` in the
//! container's frame. Its normal `n` follows the container's apparent acceleration (gravity included)
//! as a damped spherical pendulum; its offset `d` is solved from the volume by Newton steps on the
//! cross-section area with a bisection fallback, warm-started from the last offset. The liquid body
//! is the part of the container's interior (a closed triangle mesh) on the low side of the plane.
//!
//! Beyond upstream, volume moves between containers ([`transfer`]) and is conserved exactly: it is
//! bookkept in whole nanolitres. This module is pure geometry and dynamics; a MuJoCo scene feeds it
//! the acceleration and shows the result (see `runtime`/the tests).

use std::f64::consts::TAU;

pub type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn lerp(a: V3, b: V3, t: f64) -> V3 {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// A container's interior: a closed, outward-oriented triangle mesh in the container's frame (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Container {
    pub vertices: Vec<V3>,
    pub triangles: Vec<[usize; 3]>,
    /// Per triangle `a·(b×c)` and `a×b + b×c + c×a`: the signed tetrahedron volume against any
    /// reference point `o` is `(det - o·n) / 6`, one dot product per whole triangle.
    terms: Vec<(f64, V3)>,
}

impl Container {
    /// From a closed, outward-oriented triangle mesh.
    pub fn from_mesh(vertices: Vec<V3>, triangles: Vec<[usize; 3]>) -> Container {
        let terms = triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (vertices[t[0]], vertices[t[1]], vertices[t[2]]);
                let n = cross(a, b);
                let n2 = cross(b, c);
                let n3 = cross(c, a);
                (
                    dot(a, cross(b, c)),
                    [
                        n[0] + n2[0] + n3[0],
                        n[1] + n2[1] + n3[1],
                        n[2] + n2[2] + n3[2],
                    ],
                )
            })
            .collect();
        Container {
            vertices,
            triangles,
            terms,
        }
    }

    /// A tube's interior: a cylinder of `radius` from the top of a conical tip of depth `tip` up to
    /// `height` (bottom of the tip at z = 0), with `segments` sides.
    pub fn tube(radius: f64, height: f64, tip: f64, segments: usize) -> Container {
        let segments = segments.max(3);
        let mut vertices = vec![[0.0, 0.0, 0.0]];
        for (z, _) in [(tip, 0), (height, 1)] {
            for i in 0..segments {
                let a = TAU * i as f64 / segments as f64;
                vertices.push([radius * a.cos(), radius * a.sin(), z]);
            }
        }
        let top = vertices.len();
        vertices.push([0.0, 0.0, height]);
        let ring = |k: usize, i: usize| 1 + k * segments + i % segments;
        let mut triangles = Vec::new();
        for i in 0..segments {
            triangles.push([0, ring(0, i + 1), ring(0, i)]);
            triangles.push([ring(0, i), ring(0, i + 1), ring(1, i + 1)]);
            triangles.push([ring(0, i), ring(1, i + 1), ring(1, i)]);
            triangles.push([top, ring(1, i), ring(1, i + 1)]);
        }
        Container::from_mesh(vertices, triangles)
    }

    /// The same interior moved by `by` (m): a tube's interior starts above its base's thickness.
    pub fn shifted(&self, by: V3) -> Container {
        let vertices = self
            .vertices
            .iter()
            .map(|v| [v[0] + by[0], v[1] + by[1], v[2] + by[2]])
            .collect();
        Container::from_mesh(vertices, self.triangles.clone())
    }

    /// Whether `p` lies inside the interior (on its boundary counts), for a convex interior: on
    /// the inner side of every face's plane. A concave mesh would need a parity count; every
    /// container we generate (a cylinder on a cone) is convex.
    pub fn contains(&self, p: V3) -> bool {
        self.triangles.iter().all(|t| {
            let (a, b, c) = (
                self.vertices[t[0]],
                self.vertices[t[1]],
                self.vertices[t[2]],
            );
            dot(cross(sub(b, a), sub(c, a)), sub(p, a)) <= 1e-12
        })
    }

    /// Volume and cross-section area of the part with `n·x <= d` (`n` a unit vector): the
    /// divergence theorem over the clipped triangles, with the reference point on the plane so the
    /// cut face contributes no volume; the area is the cut polygon's, from the cut segments.
    pub fn volume_below(&self, n: V3, d: f64) -> (f64, f64) {
        let (v, a, _) = self.cut(n, d);
        (v, a)
    }

    /// [`Container::volume_below`] plus the centroid of the cut polygon (the surface).
    pub fn cut(&self, n: V3, d: f64) -> (f64, f64, V3) {
        let o = [n[0] * d, n[1] * d, n[2] * d];
        let mut volume = 0.0;
        let mut area = 0.0;
        let mut moment = [0.0; 3];
        let tet = |a: V3, b: V3, c: V3| dot(sub(a, o), cross(sub(b, o), sub(c, o))) / 6.0;
        // Signed heights of the vertices above the plane; on the stack for meshes of the usual size.
        let mut stack = [0.0f64; 512];
        let mut heap = Vec::new();
        let heights: &mut [f64] = if self.vertices.len() <= stack.len() {
            &mut stack[..self.vertices.len()]
        } else {
            heap.resize(self.vertices.len(), 0.0);
            &mut heap
        };
        for (h, v) in heights.iter_mut().zip(&self.vertices) {
            *h = dot(n, *v) - d;
        }
        for (t, (det, tn)) in self.triangles.iter().zip(&self.terms) {
            let s = [heights[t[0]], heights[t[1]], heights[t[2]]];
            let below = s.iter().filter(|x| **x <= 0.0).count();
            if below == 0 {
                continue;
            }
            if below == 3 {
                volume += (det - dot(o, *tn)) / 6.0;
                continue;
            }
            let p = [
                self.vertices[t[0]],
                self.vertices[t[1]],
                self.vertices[t[2]],
            ];
            // Walk the triangle's edges, keeping the part below and the two cut points
            // (fixed-size buffers: this runs for every wall triangle the plane crosses).
            let mut poly = [[0.0; 3]; 4];
            let mut np = 0;
            let mut cut = [[0.0; 3]; 2];
            let mut nc = 0;
            for i in 0..3 {
                let j = (i + 1) % 3;
                if s[i] <= 0.0 {
                    poly[np] = p[i];
                    np += 1;
                }
                if (s[i] <= 0.0) != (s[j] <= 0.0) && nc < 2 {
                    let x = lerp(p[i], p[j], s[i] / (s[i] - s[j]));
                    poly[np] = x;
                    np += 1;
                    cut[nc] = x;
                    nc += 1;
                }
            }
            for k in 1..np - 1 {
                volume += tet(poly[0], poly[k], poly[k + 1]);
            }
            if nc == 2 {
                // The segment is oriented by the triangle's winding; the cut polygon is
                // traversed the opposite way round its outward normal n. Each segment and `o`
                // make one triangle of a fan over the polygon.
                let a = dot(n, cross(sub(cut[0], o), sub(cut[1], o))) / 2.0;
                area += a;
                for k in 0..3 {
                    moment[k] += a * (o[k] + cut[0][k] + cut[1][k]) / 3.0;
                }
            }
        }
        let centroid = if area.abs() > 0.0 {
            [moment[0] / area, moment[1] / area, moment[2] / area]
        } else {
            o
        };
        (volume, area.abs(), centroid)
    }

    /// The whole interior's volume.
    pub fn capacity(&self) -> f64 {
        let (_, hi) = self.range([0.0, 0.0, 1.0]);
        self.volume_below([0.0, 0.0, 1.0], hi + 1.0).0
    }

    /// The range of `n·x` over the mesh.
    pub fn range(&self, n: V3) -> (f64, f64) {
        self.vertices
            .iter()
            .map(|v| dot(n, *v))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            })
    }

    /// The plane offset `d` with `volume_below(n, d) = volume`, within `tol` (m³), from `guess`.
    /// Newton steps on the area; a step that leaves the bracket or fails to shrink the residual is
    /// replaced by bisection. Returns the offset and the number of iterations.
    pub fn solve_offset(&self, n: V3, volume: f64, guess: f64, tol: f64) -> (f64, u32) {
        let s = self.solve(n, volume, guess, tol);
        (s.offset, s.iterations)
    }

    /// [`Container::solve_offset`] with the surface's centroid at the solution.
    pub fn solve(&self, n: V3, volume: f64, guess: f64, tol: f64) -> Solved {
        let (mut lo, mut hi) = self.range(n);
        let mut d = guess.clamp(lo, hi);
        let mut last = f64::INFINITY;
        let mut centroid = [0.0; 3];
        for it in 1..=100 {
            let (v, a, c) = self.cut(n, d);
            centroid = c;
            let r = v - volume;
            if r.abs() <= tol {
                return Solved {
                    offset: d,
                    iterations: it,
                    centroid,
                };
            }
            if r > 0.0 {
                hi = d;
            } else {
                lo = d;
            }
            let newton = if a > 0.0 { d - r / a } else { f64::NAN };
            // The first Newton step is always tried; later ones must halve the residual.
            let converging = last.is_infinite() || r.abs() < 0.5 * last;
            d = if newton > lo && newton < hi && converging {
                newton
            } else {
                (lo + hi) / 2.0
            };
            last = r.abs();
        }
        Solved {
            offset: d,
            iterations: 100,
            centroid,
        }
    }
}

/// A solved surface: its offset, the iterations it took, and its centroid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solved {
    pub offset: f64,
    pub iterations: u32,
    pub centroid: V3,
}

/// The surface normal as a damped spherical pendulum (the paper's Euler-Lagrange equations, with
/// damping ratios and the ε guard). The pendulum's resting state, the normal straight up, is a pole
/// of the spherical coordinates `n = (sin θ cos φ, sin θ sin φ, -cos θ)`, where the φ equation is
/// singular. So the state is kept as the normal and its rate in the container frame, and each step
/// integrates the equations in a chart whose pole axis is perpendicular to the current normal:
/// the normal sits on that chart's equator, the ε guard never engages in practice, and damping is
/// the same in every direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Unit normal and its rate of change (tangent to the sphere), container frame.
    pub normal: V3,
    pub rate: V3,
    /// Damping ratios of the two coordinates.
    pub damping_phi: f64,
    pub damping_theta: f64,
}

/// Guard on `sin²θ` in the φ equation (the paper's ε).
pub const EPSILON: f64 = 1e-4;

fn scale(a: V3, k: f64) -> V3 {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn unit(a: V3) -> V3 {
    scale(a, 1.0 / norm(a).max(1e-300))
}

/// An orthonormal chart frame (columns) whose third axis is perpendicular to `n`.
fn chart(n: V3) -> [V3; 3] {
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let e = axes
        .iter()
        .min_by(|a, b| dot(**a, n).abs().total_cmp(&dot(**b, n).abs()))
        .copied()
        .unwrap_or(axes[0]);
    let z = unit(sub(e, scale(n, dot(e, n))));
    let x = unit(sub(n, scale(z, dot(n, z))));
    let y = cross(z, x);
    [x, y, z]
}

fn to_chart(f: &[V3; 3], v: V3) -> V3 {
    [dot(f[0], v), dot(f[1], v), dot(f[2], v)]
}

fn from_chart(f: &[V3; 3], v: V3) -> V3 {
    [
        f[0][0] * v[0] + f[1][0] * v[1] + f[2][0] * v[2],
        f[0][1] * v[0] + f[1][1] * v[1] + f[2][1] * v[2],
        f[0][2] * v[0] + f[1][2] * v[1] + f[2][2] * v[2],
    ]
}

impl Surface {
    /// At rest with normal `n` (any length).
    pub fn new(n: V3, damping: f64) -> Surface {
        Surface {
            normal: unit(n),
            rate: [0.0; 3],
            damping_phi: damping,
            damping_theta: damping,
        }
    }

    pub fn normal(&self) -> V3 {
        self.normal
    }

    /// The paper's equations: `(φ, θ, φ̇, θ̇)` to their derivatives under `g` (chart frame).
    fn derivative(&self, s: [f64; 4], g: V3, length: f64) -> [f64; 4] {
        let [phi, theta, dphi, dtheta] = s;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let n_theta = [ct * cp, ct * sp, st];
        let n_phi = [-st * sp, st * cp, 0.0];
        let w = (norm(g) / length).sqrt();
        let ddtheta = st * ct * dphi * dphi + dot(g, n_theta) / length
            - 2.0 * self.damping_theta * w * dtheta;
        let ddphi = (-2.0 * st * ct * dtheta * dphi + dot(g, n_phi) / length
            - 2.0 * self.damping_phi * w * dphi)
            / (st * st).max(EPSILON);
        [dphi, dtheta, ddphi, ddtheta]
    }

    /// RK4 substeps for `dt`: enough for the pendulum's frequency and damping (in the equatorial
    /// chart `sin²θ` is near 1, so the ε guard does not make the equations stiff).
    pub fn substeps(&self, g: V3, length: f64, dt: f64) -> u32 {
        let w = (norm(g) / length).sqrt();
        let rate = 2.0 * self.damping_phi.max(self.damping_theta) * w + 2.0 * w;
        ((dt * rate / 0.5).ceil() as u32).clamp(1, 1000)
    }

    /// Advances by `dt` under apparent acceleration `g` (container frame, gravity included: at rest
    /// it is +9.81 up) with pendulum length `length`. Should the state ever stop being finite, it
    /// restarts at rest along `g`.
    pub fn step(&mut self, g: V3, length: f64, dt: f64) {
        let f = chart(self.normal);
        let (n, v, gc) = (
            to_chart(&f, self.normal),
            to_chart(&f, self.rate),
            to_chart(&f, g),
        );
        let theta = (-n[2]).clamp(-1.0, 1.0).acos();
        let phi = n[1].atan2(n[0]);
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let n_theta = [ct * cp, ct * sp, st];
        let n_phi = [-st * sp, st * cp, 0.0];
        let mut s = [
            phi,
            theta,
            dot(v, n_phi) / (st * st).max(EPSILON),
            dot(v, n_theta),
        ];
        let substeps = self.substeps(g, length, dt);
        let h = dt / substeps as f64;
        let add = |a: [f64; 4], k: [f64; 4], f: f64| {
            [
                a[0] + f * k[0],
                a[1] + f * k[1],
                a[2] + f * k[2],
                a[3] + f * k[3],
            ]
        };
        for _ in 0..substeps {
            let k1 = self.derivative(s, gc, length);
            let k2 = self.derivative(add(s, k1, h / 2.0), gc, length);
            let k3 = self.derivative(add(s, k2, h / 2.0), gc, length);
            let k4 = self.derivative(add(s, k3, h), gc, length);
            for i in 0..4 {
                s[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        let [phi, theta, dphi, dtheta] = s;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let n = [st * cp, st * sp, -ct];
        let v = [
            dtheta * ct * cp - dphi * st * sp,
            dtheta * ct * sp + dphi * st * cp,
            dtheta * st,
        ];
        let (n, v) = (from_chart(&f, n), from_chart(&f, v));
        if n.iter().chain(&v).all(|x| x.is_finite()) {
            self.normal = unit(n);
            self.rate = v;
        } else {
            *self = Surface::new(g, self.damping_theta);
        }
    }

    /// The small-oscillation relaxation time `1 / (ζ ω)` for apparent gravity `g` and `length`.
    pub fn relaxation_time(&self, g: f64, length: f64) -> f64 {
        1.0 / (self.damping_theta * (g / length).sqrt())
    }
}

/// Volume in whole nanolitres, so transfers add and subtract exactly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Nanolitres(pub u64);

impl Nanolitres {
    pub fn from_microlitres(ul: f64) -> Nanolitres {
        Nanolitres((ul * 1000.0).round().max(0.0) as u64)
    }
    pub fn microlitres(self) -> f64 {
        self.0 as f64 / 1000.0
    }
    /// In m³.
    pub fn cubic_metres(self) -> f64 {
        self.0 as f64 * 1e-12
    }
}

/// The liquid in one container: volume, surface dynamics and the solved offset.
#[derive(Clone, Debug, PartialEq)]
pub struct Liquid {
    pub container: Container,
    pub volume: Nanolitres,
    pub surface: Surface,
    /// Plane offset along the normal (m), container frame, as last solved; see [`Liquid::offset`].
    offset: f64,
    /// Centroid of the surface at the last solve: turning the plane about it keeps the volume to
    /// first order, so `n·centroid` is the next solve's starting guess.
    centroid: Option<V3>,
    /// The normal and volume `offset` was solved for.
    solved_for: Option<(V3, Nanolitres)>,
    /// Pendulum length (m): upstream's 3·sqrt(half width · half height) of the surface, fixed here
    /// at three container radii.
    pub length: f64,
    /// Newton/bisection iterations of the last solve.
    pub iterations: u32,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LiquidError {
    #[error("{have} µL cannot leave a container holding {left} µL")]
    NotEnough { have: f64, left: f64 },
    #[error("{volume} µL does not fit: {room} µL of room")]
    NoRoom { volume: f64, room: f64 },
}

impl Liquid {
    pub fn new(container: Container, volume: Nanolitres, damping: f64) -> Liquid {
        let (lo, hi) = container.range([0.0, 0.0, 1.0]);
        let r = container
            .vertices
            .iter()
            .map(|v| v[0].hypot(v[1]))
            .fold(0.0, f64::max);
        let mut l = Liquid {
            container,
            volume,
            surface: Surface::new([0.0, 0.0, 1.0], damping),
            offset: (lo + hi) / 2.0,
            centroid: None,
            solved_for: None,
            length: 3.0 * r.max(1e-3),
            iterations: 0,
        };
        l.offset();
        l
    }

    /// Room left, as the container's capacity minus the volume (µL).
    pub fn room(&self) -> Nanolitres {
        let cap = Nanolitres((self.container.capacity() * 1e12).floor() as u64);
        Nanolitres(cap.0.saturating_sub(self.volume.0))
    }

    /// The surface's plane offset for the current normal and volume (m, container frame). Solved
    /// on demand, warm-started from the last solve, and cached: the liquid is quasi-static, so the
    /// offset is a function of the normal and the volume, and only frames that show or check the
    /// liquid pay for it.
    pub fn offset(&mut self) -> f64 {
        let key = (self.surface.normal(), self.volume);
        if self.solved_for != Some(key) {
            let target = self.volume.cubic_metres();
            let tol = 1e-6 * self.container.capacity().max(1e-12);
            let guess = match self.centroid {
                Some(c) if self.solved_for.map(|s| s.1) == Some(self.volume) => dot(key.0, c),
                _ => self.offset,
            };
            let solved = self.container.solve(key.0, target, guess, tol);
            self.offset = solved.offset;
            self.iterations = solved.iterations;
            self.centroid = Some(solved.centroid);
            self.solved_for = Some(key);
        }
        self.offset
    }

    /// One physics step of the surface's normal: `accel` is the container's apparent acceleration
    /// in its own frame (what an accelerometer on it reads: +9.81 up at rest).
    pub fn step(&mut self, accel: V3, dt: f64) {
        self.surface.step(accel, self.length, dt);
    }

    /// Centre of the surface's cut polygon (mean of its vertices) and its radius (m), container
    /// frame: where a renderer puts the surface disk.
    pub fn surface_disk(&mut self) -> (V3, f64) {
        let offset = self.offset();
        let n = self.surface.normal();
        let mut pts: Vec<V3> = Vec::new();
        for t in &self.container.triangles {
            for i in 0..3 {
                let (a, b) = (
                    self.container.vertices[t[i]],
                    self.container.vertices[t[(i + 1) % 3]],
                );
                let (sa, sb) = (dot(n, a) - offset, dot(n, b) - offset);
                if (sa <= 0.0) != (sb <= 0.0) {
                    pts.push(lerp(a, b, sa / (sa - sb)));
                }
            }
        }
        if pts.is_empty() {
            return ([0.0, 0.0, 0.0], 0.0);
        }
        let k = pts.len() as f64;
        let c = pts.iter().fold([0.0; 3], |acc, p| {
            [acc[0] + p[0] / k, acc[1] + p[1] / k, acc[2] + p[2] / k]
        });
        let r = pts.iter().map(|p| norm(sub(*p, c))).fold(0.0, f64::max);
        (c, r)
    }
}

/// Moves `volume` from one container to another (aspirate into a tip, dispense out of it). Either
/// all of it moves or nothing does; the total is conserved exactly.
pub fn transfer(from: &mut Liquid, to: &mut Liquid, volume: Nanolitres) -> Result<(), LiquidError> {
    if from.volume < volume {
        return Err(LiquidError::NotEnough {
            have: volume.microlitres(),
            left: from.volume.microlitres(),
        });
    }
    if to.room() < volume {
        return Err(LiquidError::NoRoom {
            volume: volume.microlitres(),
            room: to.room().microlitres(),
        });
    }
    from.volume = Nanolitres(from.volume.0 - volume.0);
    to.volume = Nanolitres(to.volume.0 + volume.0);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_of_a_cylinder_match_the_formula() {
        let c = Container::tube(0.01, 0.1, 0.0, 256);
        let area = 0.5 * 256.0 * 0.01f64.powi(2) * (TAU / 256.0).sin();
        let (v, a) = c.volume_below([0.0, 0.0, 1.0], 0.05);
        assert!((v - area * 0.05).abs() < 1e-12, "{v}");
        assert!((a - area).abs() < 1e-12, "{a}");
        assert!((c.capacity() - area * 0.1).abs() < 1e-12);
    }

    #[test]
    fn the_solver_finds_the_offset_for_tilted_planes() {
        let c = Container::tube(0.014, 0.1, 0.02, 64);
        for tilt in [0.0f64, 0.3, 0.8, 1.2] {
            let n = [tilt.sin(), 0.0, tilt.cos()];
            let target = 0.4 * c.capacity();
            let (d, it) = c.solve_offset(n, target, 0.0, 1e-12);
            let (v, _) = c.volume_below(n, d);
            assert!((v - target).abs() <= 1e-12, "tilt {tilt}: {v} vs {target}");
            assert!(it < 30, "tilt {tilt}: {it} iterations");
        }
    }

    #[test]
    fn a_resting_surface_stays_level_and_a_tilted_one_swings_back() {
        let mut s = Surface::new([0.0, 0.0, 1.0], 0.05);
        for _ in 0..1000 {
            s.step([0.0, 0.0, 9.81], 0.04, 0.002);
        }
        assert!((s.normal()[2] - 1.0).abs() < 1e-12, "{:?}", s.normal());
        // Gravity tilted by 20° in the y-z plane: the normal follows it and settles there.
        let g = [
            0.0,
            9.81 * 20f64.to_radians().sin(),
            9.81 * 20f64.to_radians().cos(),
        ];
        for _ in 0..10_000 {
            s.step(g, 0.04, 0.002);
        }
        let n = s.normal();
        assert!((dot(n, g) / norm(g) - 1.0).abs() < 1e-6, "{n:?}");
    }

    #[test]
    fn a_point_is_inside_a_shifted_tube_only_within_its_walls() {
        let c = Container::tube(0.01, 0.1, 0.02, 32).shifted([0.0, 0.0, 0.002]);
        assert!(c.contains([0.0, 0.0, 0.05]));
        assert!(c.contains([0.009, 0.0, 0.05]));
        assert!(!c.contains([0.011, 0.0, 0.05]), "outside the wall");
        assert!(!c.contains([0.0, 0.0, 0.103]), "above the mouth");
        assert!(c.contains([0.0, 0.0, 0.0025]), "down in the cone's point");
        assert!(!c.contains([0.0, 0.0, 0.001]), "below the shifted bottom");
        assert!(!c.contains([0.008, 0.0, 0.005]), "outside the cone");
        assert!((c.capacity() - Container::tube(0.01, 0.1, 0.02, 32).capacity()).abs() < 1e-15);
    }

    #[test]
    fn transfers_conserve_volume_exactly() {
        let tube = Container::tube(0.014, 0.1, 0.02, 32);
        let tip = Container::tube(0.003, 0.06, 0.01, 16);
        let mut a = Liquid::new(tube, Nanolitres::from_microlitres(20_000.0), 0.03);
        let mut b = Liquid::new(tip, Nanolitres(0), 0.03);
        let total = a.volume.0 + b.volume.0;
        for ul in [200.0, 150.5, 0.001, 33.333] {
            transfer(&mut a, &mut b, Nanolitres::from_microlitres(ul)).unwrap();
            transfer(&mut b, &mut a, Nanolitres::from_microlitres(ul / 2.0)).unwrap();
            assert_eq!(a.volume.0 + b.volume.0, total);
        }
        // The surface follows the new volume.
        let d = b.offset();
        let (v, _) = b.container.volume_below(b.surface.normal(), d);
        assert!((v - b.volume.cubic_metres()).abs() <= 1e-6 * b.container.capacity());
        let too_much = Nanolitres(b.volume.0 + 1);
        let (before_a, before_b) = (a.volume, b.volume);
        assert!(matches!(
            transfer(&mut b, &mut a, too_much),
            Err(LiquidError::NotEnough { .. })
        ));
        assert_eq!((a.volume, b.volume), (before_a, before_b), "nothing moved");
    }
}
