//! One experiment configuration seen through a method with the standard and
//! the SPSM lookup: the light matrix's depth range and, for every pixel the
//! two lookups and the ray-cast truth disagree on, the post-projective
//! depths `zeta = z / w` of the receiver and of its occluder (the SPSM
//! lookup compares in `zeta`).
//!
//! ```text
//! cargo run --release --features cli --example spsm_edge -- [--preset quick|default]
//!     [--config 1] [--method optimized]
//! ```
//!
//! With `--trio FILE.png` it instead writes the README's image trio: the
//! configuration's matrix of `--method` (default `focused`), solved for the
//! preset's view, seen through a narrow camera (`--fov`, default 5°;
//! `--screen`, default 256) from the same eye, aimed at the screen window
//! across a shadow edge where the standard lookup misclassifies most, with
//! the standard lookup, the SPSM lookup and the ray-cast truth side by side
//! (the experiment's error overlay: truth's shading, false shadow red,
//! false lit blue), and prints the close-up's counts.
//!
//! With `--sgsm-closeup FILE.png` it instead writes issue 17's close-up:
//! the configuration's `--method` (default `optimized`) with its `+spsm`
//! and `+sgsm` lookups (each method solved as the experiment does), the
//! `--window`-pixel square (default 48) of the experiment's screen where
//! SPSM misclassifies most pixels that SGSM gets right, enlarged 4x:
//! SPSM, SGSM and the ray-cast truth side by side (the experiment's error
//! overlay), and prints both lookups' counts in the window and overall.
//!
//! With `--overlay DIR` it instead runs the configuration with `--method`
//! (default `focused`) and its `+spsm` and `+sgsm` lookups, writes each one's
//! error overlay to `DIR/<method>-config<N>.png` and sorts every lookup's
//! errors: false shadow / false lit, near a true shadow edge (within
//! `--edge` pixels, default 3) or interior, and for interior false shadow
//! the receiver triangle's size in map texels and its angle to the light
//! (the self-shadowing of finely tessellated curved surfaces shows there).
//! It then sorts the errors by the CPU reference of the conservative pass
//! (`sgsm::overlap`): for false light, whether the true occluder (ray cast
//! towards the light) is the triangle kept in the pixel's texel, in a
//! neighbour, or in none of the 3x3 ("not kept": the paper's missing
//! geometry); for false shadow, where the own texel's kept triangle lies.
//! `--samples N` prints every 150th error of each kind, up to N, with the
//! 3x3's kept triangles (object, area in texels², depths).

#[path = "support/mod.rs"]
mod support;

use glam::DVec3;
use lixel::experiment::{Counts, ExperimentConfig, MethodSpec, Preset, Runner};
use lixel::mesh::raycast::Ray;
use lixel::mesh::RayCaster;
use lixel::render::{ShadowLookup, SpsmOptions};
use lixel::{Light, LightMatrix};

fn main() {
    if let Err(e) = run() {
        eprintln!("spsm_edge: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    let preset = support::preset(&args)?;
    let index: usize = args.parse("--config", 1)?;
    if let Some(path) = args.value("--trio") {
        let name = args.value("--method").unwrap_or("focused");
        let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
        let fov: f64 = args.parse("--fov", 5.0)?;
        let screen: u32 = args.parse("--screen", 256)?;
        return trio(preset, index, base, (fov, screen), path);
    }
    if let Some(path) = args.value("--sgsm-closeup") {
        let name = args.value("--method").unwrap_or("optimized");
        let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
        let window: u32 = args.parse("--window", 48)?;
        return sgsm_closeup(preset, index, base, window, path);
    }
    if let Some(dir) = args.value("--overlay") {
        let name = args.value("--method").unwrap_or("focused");
        let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
        let edge: i64 = args.parse("--edge", 3)?;
        let samples: u32 = args.parse("--samples", 0)?;
        return overlay(preset, index, base, (edge, samples), dir);
    }
    let name = args.value("--method").unwrap_or("optimized");
    let base = MethodSpec::parse(name).ok_or_else(|| format!("unknown method {name:?}"))?;
    let mut config = ExperimentConfig::preset(preset);
    config.methods = vec![base, base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default()))];
    config.coverage_samples = 0;
    let (device, queue, info) = support::gpu()?;
    eprintln!("adapter: {} ({:?})", info.name, info.backend);
    let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
    let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
    let (truth, _) = runner.truths(outcome.light).map_err(|e| e.to_string())?;
    let truth = truth.ok_or("no ray-cast truth")?;
    let caster = RayCaster::new(runner.scene());
    let world_from_clip = runner.camera().clip_from_world().inverse();
    for (method, result) in &outcome.results {
        let Some(m) = result.matrix else {
            println!("{}: failed ({})", method.name(), result.note);
            continue;
        };
        let counts = result.counts.unwrap_or_default();
        println!(
            "{}: misclassified {} (false shadow {}, false lit {}); depth {:?}, unclipped {}",
            method.name(),
            counts.misclassified(),
            counts.false_shadow,
            counts.false_lit,
            m.depth,
            m.needs_unclipped_depth
        );
        let masks = runner.masks_with(&m, method.lookup()).map_err(|e| e.to_string())?;
        assert_eq!(Counts::compare(&masks, &truth), counts, "masks reproduce the run's counts");
        // Receiver and occluder zeta of every truth-shadowed pixel.
        let spsm_matrix = lixel::render::spsm::depth_matrix(&m);
        let spsm_zeta = |p: DVec3| {
            let c = spsm_matrix * p.extend(1.0);
            c.z / c.w
        };
        let mut gaps = Vec::new();
        let mut wrong_gaps = Vec::new();
        let mut spsm_gaps = Vec::new();
        let mut zetas = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..truth.depth.len() {
            if !truth.visible(i) || truth.facing[i] & 1 == 0 || truth.shadow[i] & 1 == 0 {
                continue;
            }
            let (x, y) = (i as u32 % truth.width, i as u32 / truth.width);
            let ndc = DVec3::new(
                (f64::from(x) + 0.5) / f64::from(truth.width) * 2.0 - 1.0,
                1.0 - (f64::from(y) + 0.5) / f64::from(truth.height) * 2.0,
                f64::from(truth.depth[i]),
            );
            let receiver = world_from_clip.project_point3(ndc);
            let Some(occluder) = occluder(&caster, receiver, &outcome.light) else { continue };
            let (Some(r), Some(o)) = (m.project(receiver), m.project(occluder)) else { continue };
            zetas = (zetas.0.min(r.z).min(o.z), zetas.1.max(r.z).max(o.z));
            gaps.push(r.z - o.z);
            spsm_gaps.push(spsm_zeta(receiver) - spsm_zeta(occluder));
            if masks.shadow[i] & 1 == 0 {
                wrong_gaps.push(r.z - o.z);
            }
        }
        println!(
            "  zeta over shadowed receivers and their occluders: [{:.7}, {:.7}]; receiver - occluder gap: {}; on false-lit pixels: {}",
            zetas.0,
            zetas.1,
            quantiles(&mut gaps),
            quantiles(&mut wrong_gaps)
        );
        println!("  SPSM depth row: gap {}", quantiles(&mut spsm_gaps));
        print_w(&m);
    }
    Ok(())
}

/// The closest occluder between `receiver` and the light.
fn occluder(caster: &RayCaster, receiver: DVec3, light: &Light) -> Option<DVec3> {
    let Light::Point { position } = *light else { return None };
    let to_light = (position - receiver).as_vec3();
    let origin = receiver.as_vec3() + to_light.normalize() * 1e-3;
    let hit = caster.bvh().closest_hit(&Ray { origin, direction: to_light }, 1.0)?;
    Some((origin + to_light * hit.t).as_dvec3())
}

fn quantiles(v: &mut [f64]) -> String {
    if v.is_empty() {
        return "none".into();
    }
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    format!("n {} min {:.3e} 10% {:.3e} median {:.3e} 90% {:.3e}", v.len(), q(0.0), q(0.1), q(0.5), q(0.9))
}

fn print_w(m: &LightMatrix) {
    let row = |r: usize| m.clip_from_world.row(r);
    println!("  clip z row {:?}\n  clip w row {:?}", row(2), row(3));
}

/// The README's trio (see the module docs).
fn trio(preset: Preset, index: usize, base: MethodSpec, (fov, screen): (f64, u32), path: &str) -> Result<(), String> {
    let mut config = ExperimentConfig::preset(preset);
    config.methods = vec![base];
    config.coverage_samples = 0;
    let (device, queue, _) = support::gpu()?;
    // The matrix, solved for the preset's whole view.
    let (matrix, light, window, eye) = {
        let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
        let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
        let m = outcome.results[0].1.matrix.ok_or("the method failed")?;
        let truth = runner.truths(outcome.light).map_err(|e| e.to_string())?.0.ok_or("no ray-cast truth")?;
        let masks = runner.masks_with(&m, base.lookup()).map_err(|e| e.to_string())?;
        // The 16x16 window across a shadow edge (all counted, 30-70% of it
        // shadowed in the truth) with the most pixels the standard lookup
        // misclassifies.
        let (w, h) = (truth.width as usize, truth.height as usize);
        let counted = |i: usize| truth.visible(i) && truth.facing[i] & 1 == 1;
        let mut best = (0, 0, 0);
        for y in (0..h.saturating_sub(16)).step_by(4) {
            for x in (0..w.saturating_sub(16)).step_by(4) {
                let window = || (y..y + 16).flat_map(|yy| (x..x + 16).map(move |xx| yy * w + xx));
                if !window().all(counted) {
                    continue;
                }
                let shadowed = window().filter(|&i| truth.shadow[i] & 1 == 1).count();
                if !(77..=179).contains(&shadowed) {
                    continue;
                }
                let n = window().filter(|&i| (truth.shadow[i] ^ masks.shadow[i]) & 1 == 1).count();
                if n > best.0 {
                    best = (n, x + 8, y + 8);
                }
            }
        }
        if best.0 == 0 {
            return Err("no shadow edge with standard-lookup errors in view".into());
        }
        let i = best.2 * w + best.1;
        let ndc = DVec3::new(
            (best.1 as f64 + 0.5) / w as f64 * 2.0 - 1.0,
            1.0 - (best.2 as f64 + 0.5) / h as f64 * 2.0,
            f64::from(truth.depth[i]),
        );
        let target = runner.camera().clip_from_world().inverse().project_point3(ndc);
        (m, outcome.light, target, runner.camera().eye())
    };
    // The close-up: same eye, narrow field of view, the same matrix.
    let close = ExperimentConfig { eye: Some(eye), target: Some(window), fov_y_degrees: fov, screen, ..config.clone() };
    let mut runner = Runner::new(&close, &device, &queue).map_err(|e| e.to_string())?;
    let truth = runner.truths(light).map_err(|e| e.to_string())?.0.ok_or("no ray-cast truth")?;
    let mut panels = Vec::new();
    for method in [base, base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default()))] {
        let masks = runner.masks_with(&matrix, method.lookup()).map_err(|e| e.to_string())?;
        let c = Counts::compare(&masks, &truth);
        println!(
            "{}: {} misclassified of {} (false shadow {}, false lit {})",
            method.name(),
            c.misclassified(),
            c.counted,
            c.false_shadow,
            c.false_lit
        );
        panels.push(lixel::experiment::error_overlay(&masks, &truth));
    }
    panels.push(lixel::experiment::error_overlay(&truth, &truth));
    let (w, h) = (truth.width, truth.height);
    let gap = 4;
    let mut out = image::RgbaImage::from_pixel(3 * w + 2 * gap, h, image::Rgba([255, 255, 255, 255]));
    for (k, panel) in panels.iter().enumerate() {
        image::imageops::overlay(&mut out, panel, i64::from(k as u32 * (w + gap)), 0);
    }
    out.save(path).map_err(|e| format!("{path}: {e}"))?;
    println!("target {window:?}, eye {eye:?}, fov {fov} deg; wrote {path}");
    Ok(())
}

/// Issue 17's close-up (see the module docs).
fn sgsm_closeup(preset: Preset, index: usize, base: MethodSpec, window: u32, path: &str) -> Result<(), String> {
    let mut config = ExperimentConfig::preset(preset);
    let spsm = base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default()));
    let sgsm = MethodSpec::parse(&format!("{}+sgsm", base.name())).ok_or("no +sgsm method")?;
    config.methods = vec![spsm, sgsm];
    config.coverage_samples = 0;
    let (device, queue, _) = support::gpu()?;
    let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
    let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
    let truth = runner.truths(outcome.light).map_err(|e| e.to_string())?.0.ok_or("no ray-cast truth")?;
    let (w, h) = (truth.width, truth.height);
    let mut masks = Vec::new();
    for (method, result) in &outcome.results {
        let m = result.matrix.ok_or_else(|| format!("{} failed ({})", method.name(), result.note))?;
        masks.push(runner.masks_with(&m, method.lookup()).map_err(|e| e.to_string())?);
    }
    // Per pixel: +1 where SPSM errs and SGSM does not, -1 the other way.
    let counted = |i: usize| truth.visible(i) && truth.facing[i] & 1 == 1;
    let wrong = |k: usize, i: usize| counted(i) && (masks[k].shadow[i] ^ truth.shadow[i]) & 1 == 1;
    let (mut best, mut at) = (i64::MIN, (0, 0));
    for y in (0..h.saturating_sub(window)).step_by(4) {
        for x in (0..w.saturating_sub(window)).step_by(4) {
            let mut d = 0i64;
            for yy in y..y + window {
                for xx in x..x + window {
                    let i = (yy * w + xx) as usize;
                    d += i64::from(wrong(0, i)) - i64::from(wrong(1, i));
                }
            }
            if d > best {
                (best, at) = (d, (x, y));
            }
        }
    }
    if best <= 0 {
        return Err(format!("no window where SPSM errs more than SGSM; {path} not written"));
    }
    let in_window = |k: usize| {
        (at.1..at.1 + window)
            .flat_map(|y| (at.0..at.0 + window).map(move |x| (y * w + x) as usize))
            .filter(|&i| wrong(k, i))
            .count()
    };
    for (k, (method, result)) in outcome.results.iter().enumerate() {
        let c = result.counts.unwrap_or_default();
        println!("{}: {} misclassified in the view, {} in the window", method.name(), c.misclassified(), in_window(k));
    }
    let mut panels: Vec<image::RgbaImage> = masks.iter().map(|m| lixel::experiment::error_overlay(m, &truth)).collect();
    panels.push(lixel::experiment::error_overlay(&truth, &truth));
    let scale = 4;
    let crops: Vec<image::RgbaImage> = panels
        .iter()
        .map(|p| {
            let crop = image::imageops::crop_imm(p, at.0, at.1, window, window).to_image();
            image::imageops::resize(&crop, window * scale, window * scale, image::imageops::FilterType::Nearest)
        })
        .collect();
    let gap = 4;
    let side = window * scale;
    let mut out = image::RgbaImage::from_pixel(3 * side + 2 * gap, side, image::Rgba([255, 255, 255, 255]));
    for (k, crop) in crops.iter().enumerate() {
        image::imageops::overlay(&mut out, crop, i64::from(k as u32 * (side + gap)), 0);
    }
    out.save(path).map_err(|e| format!("{path}: {e}"))?;
    println!("window {window}x{window} at ({}, {}) of {w}x{h}; wrote {path}", at.0, at.1);
    Ok(())
}

/// The `--overlay` diagnosis (see the module docs).
fn overlay(
    preset: Preset,
    index: usize,
    base: MethodSpec,
    (edge, samples): (i64, u32),
    dir: &str,
) -> Result<(), String> {
    let mut config = ExperimentConfig::preset(preset);
    let sgsm = MethodSpec::parse(&format!("{}+sgsm", base.name())).ok_or("no +sgsm method")?;
    config.methods = vec![base, base.with_lookup(ShadowLookup::Spsm(SpsmOptions::default())), sgsm];
    config.coverage_samples = 0;
    let (device, queue, _) = support::gpu()?;
    let mut runner = Runner::new(&config, &device, &queue).map_err(|e| e.to_string())?;
    let outcome = runner.run_config(index).map_err(|e| e.to_string())?;
    let (truth, _) = runner.truths(outcome.light).map_err(|e| e.to_string())?;
    let truth = truth.ok_or("no ray-cast truth")?;
    let (mesh, object_of) = runner.scene().merged();
    let names: Vec<String> = runner.scene().objects.iter().map(|o| o.name.clone()).collect();
    let bvh = lixel::mesh::raycast::Bvh::new(&mesh);
    let clip_from_world = runner.camera().clip_from_world();
    let world_from_clip = clip_from_world.inverse();
    let eye = runner.camera().eye();
    std::fs::create_dir_all(dir).map_err(|e| format!("{dir}: {e}"))?;
    let (w, h) = (i64::from(truth.width), i64::from(truth.height));
    let counted = |i: usize| truth.visible(i) && truth.facing[i] & 1 == 1;
    for (method, result) in &outcome.results {
        let Some(m) = result.matrix else {
            println!("{}: failed ({})", method.name(), result.note);
            continue;
        };
        let masks = runner.masks_with(&m, method.lookup()).map_err(|e| e.to_string())?;
        let path = format!("{dir}/{}-config{index}.png", method.name());
        lixel::experiment::error_overlay(&masks, &truth).save(&path).map_err(|e| format!("{path}: {e}"))?;
        let texels = f64::from(config.map) / 2.0;
        // The CPU reference of the conservative pass (sgsm::overlap): every
        // triangle touching each texel and the one kept there.
        let spsm_m = LightMatrix { clip_from_world: lixel::render::spsm::depth_matrix(&m), ..m };
        let projected = lixel::render::sgsm::overlap::project(runner.scene(), &spsm_m);
        let size = m.map_size.width;
        let overlap = lixel::render::sgsm::overlap::OverlapMap::new(&projected, size, m.map_size.height);
        let mut position = vec![u32::MAX; mesh.indices.len() / 3];
        for (at, (index, _)) in projected.iter().enumerate() {
            position[*index] = at as u32;
        }
        let texel_from_world = spsm_m.texel_from_world();
        // Error classes by the reference: see `class` below.
        let mut classes: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
        let mut examples_left = if matches!(method.lookup(), ShadowLookup::DepthCompare) { 0 } else { samples };
        let mut fl_seen = 0u64;
        let mut fs_seen = 0u64;
        let mut fs_examples_left = examples_left;
        // [fs edge, fs interior, fl edge, fl interior]; interior false
        // shadow by triangle area in texels² (<0.25, <1, <4, >=4) and by
        // cos(normal, to light) (<0.2, <0.5, >=0.5).
        let mut kinds = [0u64; 4];
        let mut by_area = [0u64; 4];
        let mut by_cos = [0u64; 3];
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if !counted(i) || (truth.shadow[i] ^ masks.shadow[i]) & 1 == 0 {
                    continue;
                }
                let near = (-edge..=edge).any(|dy| {
                    (-edge..=edge).any(|dx| {
                        let (xx, yy) = (x + dx, y + dy);
                        (0..w).contains(&xx)
                            && (0..h).contains(&yy)
                            && counted((yy * w + xx) as usize)
                            && (truth.shadow[(yy * w + xx) as usize] ^ truth.shadow[i]) & 1 == 1
                    })
                });
                let false_shadow = truth.shadow[i] & 1 == 0;
                kinds[usize::from(!false_shadow) * 2 + usize::from(!near)] += 1;
                let ndc = DVec3::new(
                    (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
                    1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
                    f64::from(truth.depth[i]),
                );
                let point = world_from_clip.project_point3(ndc);
                let direction = (point - eye).as_vec3();
                let Some(hit) = bvh.closest_hit(&Ray { origin: eye.as_vec3(), direction }, 1.01) else { continue };
                // A receiver triangle the map cannot project (a vertex at or
                // behind the light's w = 0 plane: the reference leaves it out)
                // has no texel position to classify the error by.
                if position[hit.triangle as usize] == u32::MAX {
                    *classes.entry("receiver not projected (w <= 0)".to_string()).or_default() += 1;
                    continue;
                }
                // Reference classification of the error.
                {
                    let p = eye + direction.as_dvec3() * f64::from(hit.t);
                    let t = texel_from_world * p.extend(1.0);
                    let pt = glam::DVec2::new(t.x / t.w, t.y / t.w);
                    let c = spsm_m.clip_from_world * p.extend(1.0);
                    let zeta = c.z / c.w;
                    let k = [pt.x.floor() as i64, pt.y.floor() as i64];
                    let kept_at = |dx: i64, dy: i64| {
                        let (x, y) = (k[0] + dx, k[1] + dy);
                        if x < 0 || y < 0 || x >= i64::from(size) || y >= i64::from(m.map_size.height) {
                            return None;
                        }
                        overlap.kept[(y * i64::from(size) + x) as usize]
                    };
                    let receiver = position[hit.triangle as usize];
                    let own = kept_at(0, 0);
                    let own_contains = own.is_some_and(|o| projected[o as usize].1.contains(pt));
                    let own_is_receiver = own == Some(receiver);
                    let mut class = String::new();
                    if false_shadow {
                        class += if near { "FS edge" } else { "FS inner" };
                        class += if own_is_receiver {
                            " own=R"
                        } else if own_contains {
                            " own∋p"
                        } else {
                            " own∌p"
                        };
                        if let Some(o) = own {
                            let d = projected[o as usize].1.depth_at(pt) - zeta;
                            class += if d < -1e-4 {
                                " own-plane<<p"
                            } else if d < -1e-5 {
                                " own-plane<p"
                            } else if d <= 1e-5 {
                                " own-plane≈p"
                            } else {
                                " own-plane>p"
                            };
                        }
                        fs_seen += 1;
                        if fs_examples_left > 0 && fs_seen.is_multiple_of(150) {
                            fs_examples_left -= 1;
                            let idx = |at: u32| projected[at as usize].0;
                            let area = |t: &lixel::render::sgsm::overlap::Projected| {
                                0.5 * (t.vertices[1] - t.vertices[0]).perp_dot(t.vertices[2] - t.vertices[0])
                            };
                            let rt = &projected[receiver as usize].1;
                            println!("    FS px ({x},{y}) near {near} R {} area {:.3} p {pt:.3} zeta {zeta:.6} R(p) {:.6} grad {:?}", names[object_of[hit.triangle as usize] as usize], area(rt), rt.depth_at(pt), rt.gradient());
                            for dy in -1..=1 {
                                for dx in -1..=1 {
                                    if let Some(q) = kept_at(dx, dy) {
                                        let t = &projected[q as usize].1;
                                        println!("      nb ({dx},{dy}) {}{} area {:.3} ∋p {} plane(p)-zeta {:.6} min-zeta {:.6}", names[object_of[idx(q)] as usize], if q == receiver { " =R" } else { "" }, area(t), t.contains(pt), t.depth_at(pt) - zeta, t.min_depth_in([k[0] + dx, k[1] + dy]).unwrap_or(9.0) - zeta);
                                    }
                                }
                            }
                        }
                    } else {
                        class += if near { "FL edge" } else { "FL inner" };
                        // The occluder: first hit towards the light.
                        let to_light = match outcome.light {
                            Light::Directional { direction } => -direction * 1e4,
                            Light::Point { position } | Light::Spot { position, .. } => position - p,
                        };
                        let origin = p + to_light.normalize() * 1e-3;
                        let occ =
                            bvh.closest_hit(&Ray { origin: origin.as_vec3(), direction: to_light.as_vec3() }, 1.0);
                        match occ {
                            None => class += " no occluder",
                            Some(o) if position[o.triangle as usize] == u32::MAX => {
                                class += " occluder not projected (w <= 0)";
                            }
                            Some(o) => {
                                let o = position[o.triangle as usize];
                                let in_list = (-1..=1)
                                    .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
                                    .find(|&(dx, dy)| kept_at(dx, dy) == Some(o));
                                let touches = overlap
                                    .lists
                                    .get((k[1] * i64::from(size) + k[0]) as usize)
                                    .is_some_and(|l| l.contains(&o));
                                class += match in_list {
                                    Some((0, 0)) => " O kept own",
                                    Some(_) => " O kept nb",
                                    None if touches => " O not kept (touches own)",
                                    None => " O not kept",
                                };
                                let occ_t = &projected[o as usize].1;
                                class += if occ_t.contains(pt) { " O∋p" } else { " O∌p" };
                                let gap = zeta - occ_t.depth_at(pt);
                                class += if gap < 1e-4 { " gap<1e-4" } else { "" };
                                class += if own_is_receiver {
                                    " own=R"
                                } else if own_contains {
                                    " own∋p"
                                } else {
                                    ""
                                };
                                fl_seen += 1;
                                if near && examples_left > 0 && fl_seen.is_multiple_of(150) {
                                    examples_left -= 1;
                                    let idx = |at: u32| projected[at as usize].0;
                                    let area = |t: &lixel::render::sgsm::overlap::Projected| {
                                        0.5 * (t.vertices[1] - t.vertices[0]).perp_dot(t.vertices[2] - t.vertices[0])
                                    };
                                    println!("    px ({x},{y}) R {} p {pt:.3} zeta {zeta:.6}; O {} area {:.3} O(p) {:.6} minO {:?}", names[object_of[hit.triangle as usize] as usize], names[object_of[idx(o)] as usize], area(occ_t), occ_t.depth_at(pt), occ_t.min_depth_in(k));
                                    for dy in -1..=1 {
                                        for dx in -1..=1 {
                                            if let Some(q) = kept_at(dx, dy) {
                                                let t = &projected[q as usize].1;
                                                println!(
                                                    "      nb ({dx},{dy}) {} area {:.3} ∋p {} plane(p) {:.6} min {:?}",
                                                    names[object_of[idx(q)] as usize],
                                                    area(t),
                                                    t.contains(pt),
                                                    t.depth_at(pt),
                                                    t.min_depth_in([k[0] + dx, k[1] + dy])
                                                );
                                            }
                                        }
                                    }
                                }
                            }
                        }
                    }
                    *classes.entry(class).or_default() += 1;
                }
                if !false_shadow || near {
                    continue;
                }
                let k = 3 * hit.triangle as usize;
                let [a, b, c] = [0, 1, 2].map(|j| mesh.positions[mesh.indices[k + j] as usize].as_dvec3());
                let (Some(pa), Some(pb), Some(pc)) = (m.project(a), m.project(b), m.project(c)) else { continue };
                let area = 0.5 * ((pb - pa).truncate().perp_dot((pc - pa).truncate())).abs() * texels * texels;
                by_area[[0.25, 1.0, 4.0].iter().filter(|&&t| area >= t).count()] += 1;
                let normal = (b - a).cross(c - a).normalize_or_zero();
                let to_light = match outcome.light {
                    Light::Directional { direction } => -direction,
                    Light::Point { position } | Light::Spot { position, .. } => position - point,
                }
                .normalize_or_zero();
                let cos = normal.dot(to_light).abs();
                by_cos[[0.2, 0.5].iter().filter(|&&t| cos >= t).count()] += 1;
            }
        }
        println!(
            "{}: {} misclassified; false shadow {} near edges / {} interior, false lit {} near edges / {} interior; \
             interior false shadow by receiver triangle area (texels²) <0.25 {} <1 {} <4 {} >=4 {}, by cos to light <0.2 {} <0.5 {} >=0.5 {}; {path}",
            method.name(),
            kinds.iter().sum::<u64>(),
            kinds[0],
            kinds[1],
            kinds[2],
            kinds[3],
            by_area[0],
            by_area[1],
            by_area[2],
            by_area[3],
            by_cos[0],
            by_cos[1],
            by_cos[2]
        );
        for (class, n) in &classes {
            if *n >= 20 {
                println!("  {n:6} {class}");
            }
        }
    }
    Ok(())
}
