//! The `lixel` command line.
//!
//! `lixel methods` computes every classical light matrix for the built-in
//! default configuration (a viewer just above a floor with objects on it, one
//! light) and prints how well each one samples the visible floor (one sample per pixel of a grid over the screen).

use std::process::ExitCode;

use glam::{DVec3, UVec2};
use lixel::score::{badness_stats, plane_samples};
use lixel::{Aabb, Camera, Light, Parameterization, PsmOptions, SceneBounds, ShadowMapSize, ShadowProblem};

const USAGE: &str = "\
usage: lixel methods [--light x,y,z] [--point] [--map N] [--samples N]

Computes every classical light matrix (normal, focused, PSM, LiSPSM,
plane-optimal) for the built-in walkthrough configuration and prints the
badness (screen pixels per texel, squared; lower is better) they give on the
visible floor (one sample per pixel of a grid over the screen).

  --light x,y,z   light direction (directional) or position (--point); default 0.4,-1,0.2
  --point         make the light a point light at --light
  --map N         shadow-map size N x N (default 400)
  --samples N     pixel grid N x N for the floor samples (default 200)

The last row, psm+readback, is PSM with its near plane pushed out to the
nearest visible floor point, as a depth readback would allow.";

struct Args {
    light: DVec3,
    point: bool,
    map: u32,
    samples: usize,
}

fn parse(mut args: impl Iterator<Item = String>) -> Result<Args, String> {
    match args.next().as_deref() {
        Some("methods") => {}
        Some("-h" | "--help") | None => return Err(String::new()),
        Some(other) => return Err(format!("unknown command {other:?}")),
    }
    let mut parsed = Args { light: DVec3::new(0.4, -1.0, 0.2), point: false, map: 400, samples: 200 };
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--light" => {
                let v: Vec<f64> = value()?
                    .split(',')
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("--light: {e}"))?;
                let [x, y, z] = v[..] else { return Err("--light needs x,y,z".into()) };
                parsed.light = DVec3::new(x, y, z);
            }
            "--point" => parsed.point = true,
            "--map" => parsed.map = value()?.parse().map_err(|e| format!("--map: {e}"))?,
            "--samples" => parsed.samples = value()?.parse().map_err(|e| format!("--samples: {e}"))?,
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown flag {other:?}")),
        }
    }
    Ok(parsed)
}

fn run(args: &Args) -> Result<(), lixel::LixelError> {
    // The paper's walkthrough: viewer a little above a floor with objects on it.
    let camera = Camera::look_at(
        DVec3::new(0.0, 1.7, 20.0),
        DVec3::new(0.0, 1.2, 0.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(750, 750),
        0.1,
        200.0,
    )?;
    let floor = Aabb::from_corners(DVec3::new(-40.0, 0.0, -40.0), DVec3::new(40.0, 0.0, 40.0));
    let objects = Aabb::from_corners(DVec3::new(-30.0, 0.0, -30.0), DVec3::new(30.0, 6.0, 30.0));
    let bounds = SceneBounds { casters: objects, receivers: objects.union(&floor) };
    let light = if args.point { Light::point(args.light) } else { Light::directional(args.light) };
    let problem = ShadowProblem::new(camera, light, bounds, ShadowMapSize::square(args.map))?;

    let n = u32::try_from(args.samples.max(2)).unwrap_or(u32::MAX);
    let floor_plane = lixel::geometry::Plane::from_point_normal(DVec3::ZERO, DVec3::Y);
    let floor_samples = plane_samples(&camera, &floor_plane, &floor, UVec2::new(n, n));
    // What a depth readback would supply to PSM: the nearest visible receiver.
    let nearest = floor_samples.iter().map(|(p, _)| camera.view_depth(*p)).fold(f64::INFINITY, f64::min);
    println!(
        "{} floor samples (one per pixel of a {n}x{n} grid), {}x{} map, {light:?}",
        floor_samples.len(),
        args.map,
        args.map
    );
    println!("{:<15} {:>12} {:>12} {:>12}  fallback", "method", "median b", "mean b", "max b");
    let psm_near = Parameterization::Psm(PsmOptions { min_view_depth: nearest.is_finite().then_some(nearest) });
    let methods = Parameterization::ALL_DEFAULT.iter().map(|p| (p.method().name(), *p));
    for (name, parameterization) in methods.chain([("psm+readback", psm_near)]) {
        match problem.solve(&parameterization) {
            Ok(matrix) => {
                let stats = badness_stats(&matrix, &camera, floor_samples.iter().copied());
                let (median, mean, max) = stats.map_or((f64::NAN, f64::NAN, f64::NAN), |s| (s.median, s.mean, s.max));
                let fallback = matrix.fallback.map_or_else(|| "-".to_string(), |f| format!("{f:?}"));
                println!("{name:<15} {median:>12.4} {mean:>12.4} {max:>12.4}  {fallback}");
            }
            Err(e) => println!("{name:<15} error: {e}"),
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = match parse(std::env::args().skip(1)) {
        Ok(args) => args,
        Err(message) => {
            if !message.is_empty() {
                eprintln!("error: {message}\n");
            }
            eprintln!("{USAGE}");
            return if message.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(2) };
        }
    };
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
