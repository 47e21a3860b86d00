//! Initial particles of a scene: fluid blocks and boundary walls on the particle lattice.

use crate::scene::inlet::Inlet;
use crate::scene::particle_limit::ParticleLimit;
use crate::scene::{Boundary, DensityEquation, DensityKernelKind, Pressure, Scene, SceneError};
use coil_kernels::smoothing::SmoothingKernels;
use coil_kernels::{Real, Vec3};
use std::collections::HashMap;

/// Particle positions (m) and velocities (m/s) at t = 0.
#[derive(Debug, Clone, Default)]
pub struct InitialParticles {
    pub boundary: Vec<[f64; 3]>,
    /// Each boundary particle's mirror image through the surface of its wall (m): the point
    /// whose fluid it mirrors under `simulation.walls = "mirrored"`.
    pub boundary_mirror: Vec<[f64; 3]>,
    pub fluid: Vec<[f64; 3]>,
    pub fluid_velocity: Vec<[f64; 3]>,
}

/// Lattice points `min + (i + 1/2) s` for `i` in `lo..hi` along each axis that `keep` accepts,
/// given their index and position.
fn lattice(
    min: [f64; 3],
    s: f64,
    lo: [i64; 3],
    hi: [i64; 3],
    mut keep: impl FnMut([i64; 3], [f64; 3]) -> bool,
    out: &mut Vec<[f64; 3]>,
) {
    for k in lo[2]..hi[2] {
        for j in lo[1]..hi[1] {
            for i in lo[0]..hi[0] {
                let x = [min[0] + (i as f64 + 0.5) * s, min[1] + (j as f64 + 0.5) * s, min[2] + (k as f64 + 0.5) * s];
                if keep([i, j, k], x) {
                    out.push(x);
                }
            }
        }
    }
}

/// Layer distances (in spacings) that keep a jet a continuum: farther apart its particles
/// fall as a string of beads, closer they start compressed to several times rho0. A nozzle
/// narrower than a spacing holds a single lattice point and lands outside.
const MIN_LAYER_DISTANCE: f64 = 0.5;
const MAX_LAYER_DISTANCE: f64 = 2.0;

/// Lattice points in a box of `n` cells.
fn points(n: [i64; 3]) -> f64 {
    n.iter().map(|&c| c.max(0) as f64).product()
}

/// Refuses a shape (`field`) of up to `points` particles that could take the particles made so
/// far past `limit`, before any of it is made.
fn room(p: &InitialParticles, points: f64, limit: &ParticleLimit, field: String, file: &str) -> Result<(), SceneError> {
    let before = p.boundary.len() + p.fluid.len();
    if before as f64 + points <= limit.most {
        return Ok(());
    }
    Err(SceneError {
        file: file.into(),
        field,
        reason: format!(
            "its lattice holds up to {points:.3e} particles, with the {before} before it more than the run can hold: {}; coarsen material.particle_spacing_m or make it smaller",
            limit.why
        ),
    })
}

/// Gives the fluid particles added since `before` their initial velocity and refuses them if
/// any sits in a wall or on fluid an earlier shape made; `field` names the fluid shape in the
/// error, `walls` the scene's walls.
fn settle(
    p: &mut InitialParticles,
    before: usize,
    velocity: [f64; 3],
    walls: &Walls,
    field: String,
    file: &str,
) -> Result<(), SceneError> {
    let err = |reason: String| Err(SceneError { file: file.into(), field: field.clone(), reason });
    p.fluid_velocity.resize(p.fluid.len(), velocity);
    let s = walls.spacing;
    if let Some(q) = overlap(&p.boundary, &p.fluid[before..], s) {
        return err(format!("overlaps a wall at {q:?}: fluid must start inside the walls, not in them"));
    }
    if let Some((q, k)) = p.fluid[before..].iter().find_map(|&q| walls.holding(q).map(|k| (q, k))) {
        return err(format!("reaches into the walls of boundary[{k}] at {q:?}: fluid must start inside the walls, not in them"));
    }
    if let Some(q) = overlap(&p.fluid[..before], &p.fluid[before..], s) {
        return err(format!("overlaps the fluid of an earlier shape at {q:?}: particles would start on top of each other"));
    }
    Ok(())
}

/// The solid regions of a scene's walls: where their particles lie.
struct Walls<'a> {
    boundaries: &'a [Boundary],
    domain: &'a crate::scene::Domain,
    spacing: f64,
    /// The depth of the wall layers (m).
    depth: f64,
}

impl Walls<'_> {
    /// The boundary whose wall layers hold point `q` (m), if any.
    fn holding(&self, q: [f64; 3]) -> Option<usize> {
        let (d, s) = (self.depth, self.spacing);
        // Points on a wall's surface are the fluid's: the first fluid layer lies s/2 inside it.
        let inside = |lo: f64, x: f64, hi: f64| x > lo + 1e-9 * s && x < hi - 1e-9 * s;
        self.boundaries.iter().position(|b| match *b {
            Boundary::Box { min_m, max_m, open_top } => {
                let top = if open_top { max_m[1] } else { max_m[1] + d };
                let in_outer = (0..3).all(|a| {
                    let (lo, hi) =
                        if self.domain.periodic[a] { (f64::NEG_INFINITY, f64::INFINITY) } else { (min_m[a] - d, max_m[a] + d) };
                    inside(lo, q[a], if a == 1 { top.min(hi) } else { hi })
                });
                let in_interior = (0..3).all(|a| q[a] >= min_m[a] && q[a] <= max_m[a]);
                in_outer && !in_interior
            }
            Boundary::Plate { height_m, min_xz_m, max_xz_m } => {
                let lo = min_xz_m.unwrap_or([self.domain.min_m[0], self.domain.min_m[2]]);
                let hi = max_xz_m.unwrap_or([self.domain.max_m[0], self.domain.max_m[2]]);
                inside(height_m - d, q[1], height_m) && inside(lo[0], q[0], hi[0]) && inside(lo[1], q[2], hi[1])
            }
        })
    }
}

/// Cells of the lattice that fit in `extent`: a block that is not a whole number of spacings
/// is rounded to the nearest one.
fn cells(extent: f64, s: f64) -> i64 {
    (extent / s).round().max(1.0) as i64
}

/// Wall layers (paper Sec. III-B: total width at least the support radius). Layer k, at depth
/// (k + 1/2) s below the wall, meets the fluid (at s/2 and above) when (k + 1) s < h, and its own
/// density by Eq. (5) needs layers down to depth (k + 1/2) s + h; covering both for the deepest
/// such layer gives 2 ceil(h/s) - 2 layers, and never fewer than the paper's ceil(h/s). With
/// h = 2 s that is 2, and every boundary particle a fluid particle sees has full support.
pub fn boundary_layers(spacing: f64, support_radius: f64) -> i64 {
    // The tolerance keeps h = 2 s, computed as 2.0000000001 s, at 2 spacings.
    let per_support = (support_radius / spacing - 1e-9).ceil() as i64;
    (2 * per_support - 2).max(per_support)
}

/// The fastest the fluid starts (m/s): the fastest jet, or the fastest initial velocity.
pub fn fastest_start_speed(scene: &Scene, initial: &InitialParticles) -> f64 {
    let jet = scene.inlets.iter().map(|i| i.speed_m_s).fold(0.0, f64::max);
    initial.fluid_velocity.iter().map(|v| v.iter().map(|c| c * c).sum::<f64>().sqrt()).fold(jet, f64::max)
}

/// Builds the particles of `scene` and checks they fit the domain, do not overlap, and leave
/// room for the fluid capacity on this machine.
pub fn initial_particles(scene: &Scene, file: &str) -> Result<InitialParticles, SceneError> {
    initial_particles_within(scene, file, &ParticleLimit::of(scene))
}

/// [`initial_particles`] within `limit`.
pub fn initial_particles_within(scene: &Scene, file: &str, limit: &ParticleLimit) -> Result<InitialParticles, SceneError> {
    let s = scene.material.particle_spacing_m;
    let layers = boundary_layers(s, scene.support_radius());
    let mut p = InitialParticles::default();
    let err = |field: String, reason: String| SceneError { file: file.into(), field, reason };

    let periodic = scene.domain.periodic;
    let walls = Walls { boundaries: &scene.boundaries, domain: &scene.domain, spacing: s, depth: layers as f64 * s };
    for (k, b) in scene.boundaries.iter().enumerate() {
        let before = p.boundary.len();
        match *b {
            Boundary::Box { min_m, max_m, open_top } => {
                // A box has no walls across a periodic axis: there the fluid wraps around.
                let n = [0, 1, 2].map(|a| cells(max_m[a] - min_m[a], s));
                let reach = |a: usize| if periodic[a] { 0 } else { layers };
                let lo = [0, 1, 2].map(|a| -reach(a));
                let hi = [n[0] + reach(0), if open_top { n[1] } else { n[1] + reach(1) }, n[2] + reach(2)];
                room(&p, points([0, 1, 2].map(|a| hi[a] - lo[a])) - points(n), limit, format!("boundary[{k}]"), file)?;
                lattice(min_m, s, lo, hi, |c, _| (0..3).any(|a| c[a] < 0 || c[a] >= n[a]), &mut p.boundary);
                // Through the nearest point of the interior: a face, an edge or a corner.
                let interior_max = [0, 1, 2].map(|a| min_m[a] + n[a] as f64 * s);
                p.boundary_mirror.extend(
                    p.boundary[before..].iter().map(|x| [0, 1, 2].map(|a| 2.0 * x[a].clamp(min_m[a], interior_max[a]) - x[a])),
                );
            }
            Boundary::Plate { height_m, min_xz_m, max_xz_m } => {
                let d = &scene.domain;
                let min_xz = min_xz_m.unwrap_or([d.min_m[0], d.min_m[2]]);
                let max_xz = max_xz_m.unwrap_or([d.max_m[0], d.max_m[2]]);
                let n = [cells(max_xz[0] - min_xz[0], s), cells(max_xz[1] - min_xz[1], s)];
                let min = [min_xz[0], height_m - layers as f64 * s, min_xz[1]];
                room(&p, points([n[0], layers, n[1]]), limit, format!("boundary[{k}]"), file)?;
                lattice(min, s, [0, 0, 0], [n[0], layers, n[1]], |_, _| true, &mut p.boundary);
                let top_max = [min_xz[0] + n[0] as f64 * s, min_xz[1] + n[1] as f64 * s];
                p.boundary_mirror.extend(p.boundary[before..].iter().map(|x| {
                    let nearest = [x[0].clamp(min_xz[0], top_max[0]), height_m, x[2].clamp(min_xz[1], top_max[1])];
                    [0, 1, 2].map(|a| 2.0 * nearest[a] - x[a])
                }));
            }
        }
        if let Some(q) = p.boundary[before..].iter().find(|q| !scene.domain.contains(**q)) {
            return Err(err(
                format!("boundary[{k}]"),
                format!("its {layers} wall layers reach {q:?}, outside the domain box; enlarge the domain"),
            ));
        }
        if let Some(q) = overlap(&p.boundary[..before], &p.boundary[before..], s) {
            return Err(err(
                format!("boundary[{k}]"),
                format!("its walls overlap an earlier boundary's at {q:?}: wall particles would lie on top of each other"),
            ));
        }
    }

    for (k, b) in scene.fluid_blocks.iter().enumerate() {
        let before = p.fluid.len();
        let n = [0, 1, 2].map(|a| cells(b.max_m[a] - b.min_m[a], s));
        room(&p, points(n), limit, format!("fluid_block[{k}]"), file)?;
        lattice(b.min_m, s, [0; 3], n, |_, _| true, &mut p.fluid);
        settle(&mut p, before, b.velocity_m_s, &walls, format!("fluid_block[{k}]"), file)?;
    }
    for (k, t) in scene.fluid_tori.iter().enumerate() {
        let before = p.fluid.len();
        let (c, big, small) = (t.centre_m, t.major_radius_m, t.minor_radius_m);
        let min = [c[0] - big - small, c[1] - small, c[2] - big - small];
        let n = [cells(2.0 * (big + small), s), cells(2.0 * small, s), cells(2.0 * (big + small), s)];
        room(&p, points(n), limit, format!("fluid_torus[{k}]"), file)?;
        lattice(
            min,
            s,
            [0; 3],
            n,
            |_, x| {
                let q = [0, 1, 2].map(|a| x[a] - c[a]);
                let ring = (q[0] * q[0] + q[2] * q[2]).sqrt() - big;
                ring * ring + q[1] * q[1] <= small * small
            },
            &mut p.fluid,
        );
        settle(&mut p, before, t.velocity_m_s, &walls, format!("fluid_torus[{k}]"), file)?;
    }
    for (k, c) in scene.fluid_cylinders.iter().enumerate() {
        let before = p.fluid.len();
        let (b, r) = (c.base_centre_m, c.radius_m);
        let min = [b[0] - r, b[1], b[2] - r];
        let n = [cells(2.0 * r, s), cells(c.height_m, s), cells(2.0 * r, s)];
        room(&p, points(n), limit, format!("fluid_cylinder[{k}]"), file)?;
        lattice(min, s, [0; 3], n, |_, x| (x[0] - b[0]).powi(2) + (x[2] - b[2]).powi(2) <= r * r, &mut p.fluid);
        settle(&mut p, before, c.velocity_m_s, &walls, format!("fluid_cylinder[{k}]"), file)?;
    }
    let mass = calibrated_mass(scene.material.rest_density_kg_m3, s, scene.support_radius(), scene.material.density_kernel);
    let mut smallest_layer = usize::MAX;
    for (k, config) in scene.inlets.iter().enumerate() {
        let inlet = Inlet::new(config, s, scene.support_radius(), rest_volume(scene, mass), scene.material.rest_density_kg_m3);
        smallest_layer = smallest_layer.min(inlet.layer_size());
        let end = scene.simulation.end_time_s;
        let (start, stop) = inlet.active();
        for t in inlet.turning_times(start, stop.min(end)) {
            for q in inlet.reach(t) {
                if !scene.domain.contains(q) {
                    return Err(err(
                        format!("inlet[{k}]"),
                        format!(
                            "its nozzle and tube reach {q:?} at t = {t} s, outside the domain box, where nothing can be injected; move or narrow the nozzle, or enlarge the domain"
                        ),
                    ));
                }
                if let Some(b) = walls.holding(q) {
                    return Err(err(
                        format!("inlet[{k}]"),
                        format!("its nozzle and tube reach into the walls of boundary[{b}] at {q:?} at t = {t} s; move the nozzle out of them"),
                    ));
                }
            }
        }
        let apart = inlet.layer_distance() / s;
        if !(MIN_LAYER_DISTANCE..=MAX_LAYER_DISTANCE).contains(&apart) {
            return Err(err(
                format!("inlet[{k}].nozzle"),
                format!(
                    "at spacing {s} m its section holds {} lattice point(s), so to deliver A U at rest density its layers would be {apart:.2} spacings apart ({MIN_LAYER_DISTANCE} to {MAX_LAYER_DISTANCE} make a continuous jet); widen it to a radius (circle), or a width and depth (rectangle), of at least a spacing, or refine material.particle_spacing_m",
                    inlet.layer_size()
                ),
            ));
        }
    }
    if p.fluid.is_empty() && scene.inlets.is_empty() {
        return Err(err(
            "(scene)".into(),
            "has no fluid: no fluid_block, fluid_torus or fluid_cylinder holds a lattice point and there is no inlet".into(),
        ));
    }
    let capacity = scene.simulation.max_fluid_particles.unwrap_or(p.fluid.len());
    if !scene.inlets.is_empty() && capacity < p.fluid.len() + smallest_layer {
        return Err(err(
            "simulation.max_fluid_particles".into(),
            format!(
                "the fluid capacity {capacity} leaves no room for an inlet's layer of {smallest_layer} particles beyond the {} of the initial fluid: the inlets would inject nothing; raise it (`coil check` says what the end time needs)",
                p.fluid.len()
            ),
        ));
    }
    if let Some(budget) = scene.simulation.max_fluid_particles {
        if budget < p.fluid.len() {
            return Err(err(
                "simulation.max_fluid_particles".into(),
                format!("{budget} is below the {} particles of the initial fluid", p.fluid.len()),
            ));
        }
        if (p.boundary.len() + budget) as f64 > limit.most {
            return Err(err(
                "simulation.max_fluid_particles".into(),
                format!("{budget} fluid and {} wall particles are more than the run can hold: {}", p.boundary.len(), limit.why),
            ));
        }
    }
    Ok(p)
}

/// The first of `fluid` closer than s/2 to a boundary particle.
fn overlap(boundary: &[[f64; 3]], fluid: &[[f64; 3]], s: f64) -> Option<[f64; 3]> {
    let key = |q: [f64; 3]| q.map(|c| (c / s).floor() as i64);
    let mut cells: HashMap<[i64; 3], Vec<[f64; 3]>> = HashMap::new();
    for &b in boundary {
        cells.entry(key(b)).or_default().push(b);
    }
    let limit2 = 0.25 * s * s * (1.0 - 1e-9);
    fluid.iter().copied().find(|&f| {
        let c = key(f);
        (-1..=1).any(|dz| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    cells
                        .get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        .is_some_and(|v| v.iter().any(|b| (0..3).map(|a| (b[a] - f[a]).powi(2)).sum::<f64>() < limit2))
                })
            })
        })
    })
}

/// Particle mass (kg) that makes the density (Eq. (5) with `kernel`) of a full cubic lattice of
/// spacing `s` equal rho0, so fluid at rest starts at zero pressure (m = rho0 s^3 would leave
/// it a few percent off, since the lattice sum of W is not exactly 1/s^3).
pub fn calibrated_mass(rest_density: f64, spacing: f64, support_radius: f64, kernel: DensityKernelKind) -> f64 {
    let kernels = SmoothingKernels::<f64>::new(support_radius);
    let n = (support_radius / spacing).ceil() as i64;
    let mut sum = 0.0;
    for k in -n..=n {
        for j in -n..=n {
            for i in -n..=n {
                let r2 = ((i * i + j * j + k * k) as f64) * spacing * spacing;
                sum += match kernel {
                    DensityKernelKind::Poly6 => kernels.poly6(r2),
                    DensityKernelKind::Spiky => kernels.spiky(r2),
                };
            }
        }
    }
    rest_density / sum
}

/// The volume (m^3) a particle of `mass` (kg) fills at rho0. Where density is summed (Eq. 5)
/// it is a lattice cell, s^3: the calibrated mass makes the full cubic lattice of spacing s sum
/// to rho0, and a lattice packed closer sums above it: with m / rho0 instead (0.81 s^3 with the
/// spiky kernel) a 5-across jet's layers lay 0.86 spacings apart and summed to 1.09 to 1.12
/// rho0 in the nozzle, which a pressure solve then released at once, kicking the layer below
/// the exit from 1 to 1.6 m/s. Where pressure is solved on the continuity density it is a
/// lattice cell as well: the kernels are calibrated on that lattice with volumes m / rho0
/// (`calibrated_kernels`), and on the lattice of cells m / rho0, 0.93 spacings, their gradients
/// read 1.24 times a linear field's, and the viscous force, two gradients, about 1.5 times the
/// liquid's; on the lattice the fluid also packs as the walls do. Where the
/// continuity density meets the equation of state each particle starts at rho0 and its volume
/// is m / rho0.
pub fn rest_volume(scene: &Scene, mass: f64) -> f64 {
    match (scene.material.density_equation, scene.simulation.pressure) {
        (DensityEquation::Summation, _) | (_, Pressure::DivergenceFree) => scene.material.particle_spacing_m.powi(3),
        (DensityEquation::Continuity, Pressure::WeaklyCompressible) => mass / scene.material.rest_density_kg_m3,
    }
}

/// The kernels of support `support_radius` calibrated on the cubic lattice of `spacing` (m),
/// as `calibrated_mass` calibrates the mass: on that lattice, with volumes m / rho0,
/// - Eq. (8)'s sum of (f_j - f_i) grad W over a linear field f gives grad f exactly (the raw
///   spiky kernel gives 0.947 of it at h = 2 s, so Eq. (8) then (9) would see the viscosity
///   10 % low), and the pressure force of Eq. (7) uses the same corrected gradient;
/// - the viscosity-kernel sum of (f_j - f_i) lap W over f = y^2 gives lap f = 2 exactly (the raw
///   kernel gives 1.957), and so does Morris's.
pub fn calibrated_kernels<R: Real>(
    rest_density: f64,
    spacing: f64,
    support_radius: f64,
    kernel: DensityKernelKind,
) -> SmoothingKernels<R> {
    let raw = SmoothingKernels::<f64>::new(support_radius);
    let volume = calibrated_mass(rest_density, spacing, support_radius, kernel) / rest_density;
    let n = (support_radius / spacing).ceil() as i64;
    let (mut gradient, mut laplacian, mut morris) = (0.0, 0.0, 0.0);
    for k in -n..=n {
        for j in -n..=n {
            for i in -n..=n {
                // Neighbor x_j at (i, j, k) s, particle i at the origin: r_ij = -x_j.
                let y = j as f64 * spacing;
                let r2 = ((i * i + j * j + k * k) as f64) * spacing * spacing;
                let r_ij = Vec3::new(-(i as f64) * spacing, -y, -(k as f64) * spacing);
                gradient += volume * y * raw.spiky_gradient(r_ij, r2).y;
                laplacian += volume * y * y * raw.viscosity_laplacian(r2);
                morris += volume * y * y * raw.morris_laplacian(r2);
            }
        }
    }
    SmoothingKernels::<R>::new(support_radius).corrected(1.0 / gradient, 2.0 / laplacian, 2.0 / morris)
}
