//! `lixel experiment --preset quick` end to end: the report files, their
//! invariants, determinism and `--resume`.
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use lixel::experiment::{self, ExperimentConfig, MethodSpec, Preset};

fn config(out: &std::path::Path) -> ExperimentConfig {
    ExperimentConfig {
        out: out.to_path_buf(),
        configs: 4,
        equivalence_configs: 1,
        ..ExperimentConfig::preset(Preset::Quick)
    }
}

fn csv_rows(path: &std::path::Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path).unwrap().lines().skip(1).map(|l| l.split(',').map(str::to_string).collect()).collect()
}

#[test]
fn quick_preset_writes_a_consistent_report_deterministically_and_resumes() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-experiment-{}", std::process::id()));
    let (first, second) = (dir.join("first"), dir.join("second"));
    let _ = std::fs::remove_dir_all(&dir);

    let c = config(&first);
    let summary = experiment::run(&c, &device, &queue, &mut |_| {}).unwrap();
    for file in ["summary.csv", "configs.csv", "report.md", "settings.json", "sorted-errors.png", "equivalence.png"] {
        assert!(first.join(file).is_file(), "{file} missing");
    }
    let images = std::fs::read_dir(first.join("images")).unwrap().count();
    assert!(images >= c.methods.len(), "only {images} images");

    // summary.csv: one row per method, the required columns first.
    let header = std::fs::read_to_string(first.join("summary.csv")).unwrap();
    assert!(header.starts_with("method,configs,mean_misclassified,total_misclassified,percent_more_than_optimized"));
    let summary_rows = csv_rows(&first.join("summary.csv"));
    assert_eq!(summary_rows.len(), c.methods.len());
    for m in MethodSpec::ALL {
        assert!(summary_rows.iter().any(|r| r[0] == m.name()), "{} missing from summary.csv", m.name());
    }
    // mean_visibility_error (the coverage truth, 32 sub-samples): a share
    // in (0, 1) for every method, the last column of summary.csv.
    assert!(header.lines().next().unwrap().ends_with(",mean_visibility_error"));
    for m in &summary.methods {
        let e = m.mean_visibility_error.expect("the quick preset traces the coverage truth");
        assert!(e > 0.0 && e < 1.0, "{:?}: {e}", m.method);
    }
    // configs.csv: every configuration has every method; counts within the pixel totals.
    let rows = csv_rows(&first.join("configs.csv"));
    assert_eq!(rows.len(), c.configs * c.methods.len());
    let pixels = u64::from(c.screen) * u64::from(c.screen);
    for r in &rows {
        let (counted, mis): (u64, u64) = (r[5].parse().unwrap(), r[6].parse().unwrap());
        let (false_shadow, false_lit): (u64, u64) = (r[7].parse().unwrap(), r[8].parse().unwrap());
        assert!(counted <= pixels && mis <= counted && mis == false_shadow + false_lit, "{r:?}");
        assert!(counted > 0, "nothing counted: {r:?}");
    }
    // The two ground truths agree on at least 99% of counted pixels.
    let agreement = summary.truth_agreement.expect("the quick preset computes both truths");
    assert!(agreement >= 0.99, "truths agree on only {:.3}%", 100.0 * agreement);
    let report = std::fs::read_to_string(first.join("report.md")).unwrap();
    assert!(report.contains("| all |") && report.contains("worst 10% of optimized"));
    // The per-stage breakdown: the truth and the method renders took time.
    use lixel::experiment::RunStage;
    assert!(report.contains("## Where the time went") && report.contains("| ground truth |"), "{report}");
    assert!(!summary.stages.get(RunStage::Truth).is_zero() && !summary.stages.get(RunStage::Lookups).is_zero());
    assert!(summary.stages.wall() <= summary.elapsed, "{:?} > {:?}", summary.stages, summary.elapsed);

    // Same seed, same configs.csv; an interrupted run resumes to the same file.
    let c2 = config(&second);
    let _ = experiment::run(&ExperimentConfig { configs: 2, ..c2.clone() }, &device, &queue, &mut |_| {}).unwrap();
    // Simulate an interruption in the middle of configuration 1.
    let path = second.join("configs.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let keep: Vec<&str> = text.lines().take(1 + c.methods.len() + 2).collect();
    std::fs::write(&path, keep.join("\n") + "\n").unwrap();
    let mut done = Vec::new();
    let _ =
        experiment::run(&ExperimentConfig { resume: true, ..c2 }, &device, &queue, &mut |p| done.push(p.done)).unwrap();
    assert_eq!(done.first(), Some(&1), "configuration 0 should have been kept");
    assert_eq!(
        std::fs::read_to_string(first.join("configs.csv")).unwrap(),
        std::fs::read_to_string(&path).unwrap(),
        "a resumed run with the same seed must reproduce configs.csv"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The lookup suffixes are as deterministic as the standard lookup: two
/// runs of the quick preset's first configurations with the antialiased
/// and supersampled lookups write the same `configs.csv` (the antialiased
/// passes once took the first match from tile lists whose order comes from
/// atomics, and their visibility sums differed from run to run).
#[test]
fn lookup_suffixes_are_deterministic() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-experiment-lookups-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let methods: Vec<MethodSpec> = ["focused+aa32", "optimized+aa32", "focused+spsm", "focused+sgsm", "focused+ss8"]
        .iter()
        .map(|n| MethodSpec::parse(n).unwrap())
        .collect();
    let mut files = Vec::new();
    for run in ["a", "b"] {
        let c =
            ExperimentConfig { configs: 2, equivalence_configs: 0, methods: methods.clone(), ..config(&dir.join(run)) };
        let _ = experiment::run(&c, &device, &queue, &mut |_| {}).unwrap();
        files.push(std::fs::read_to_string(dir.join(run).join("configs.csv")).unwrap());
    }
    assert!(files[0] == files[1], "two runs differ:\n{}\n{}", files[0], files[1]);
    // The report gives the antialiased methods' pair-list use (issue 18's memory goal).
    let report = std::fs::read_to_string(dir.join("a").join("report.md")).unwrap();
    assert!(report.contains("Pair lists of the antialiased lookups"), "{report}");
    // Each method has a row in the method table; the antialiased ones a second in the pair-list table.
    let rows = |name: &str| report.lines().filter(|l| l.starts_with(&format!("| {name} | 2 | "))).count();
    assert_eq!((rows("focused+aa32"), rows("optimized+aa32"), rows("focused+spsm")), (2, 2, 1), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Several configurations at once (`jobs`) change no result: the quick
/// preset with 1 and 3 workers (4 configurations: uneven per worker; more
/// workers than this machine's cores) writes the same `summary.csv`, `configs.csv`,
/// equivalence figures and pictures, and the stage table says how many
/// workers ran.
#[test]
fn workers_write_the_report_of_one_worker() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-experiment-jobs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut summaries = Vec::new();
    for jobs in [1, 3] {
        let c = ExperimentConfig { jobs, configs: 4, equivalence_configs: 2, ..config(&dir.join(jobs.to_string())) };
        summaries.push(experiment::run(&c, &device, &queue, &mut |_| {}).unwrap());
    }
    let read = |jobs: &str, file: &str| std::fs::read(dir.join(jobs).join(file)).unwrap();
    for file in ["summary.csv", "configs.csv", "sorted-errors.png", "equivalence.png"] {
        assert!(read("1", file) == read("3", file), "{file} differs between 1 and 3 workers");
    }
    let images = |jobs: &str| {
        let mut names: Vec<_> = std::fs::read_dir(dir.join(jobs).join("images"))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        names
    };
    assert_eq!(images("1"), images("3"));
    for name in images("1") {
        assert!(read("1", &format!("images/{name}")) == read("3", &format!("images/{name}")), "{name} differs");
    }
    // The report up to its timing sections is the same text.
    let head = |jobs: &str| {
        let text = String::from_utf8(read(jobs, "report.md")).unwrap();
        text.split("## Where the time went")
            .next()
            .unwrap()
            .lines()
            .filter(|l| !l.contains("Run time"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(head("1"), head("3"));
    use lixel::experiment::RunStage;
    let (one, three) = (&summaries[0].stages, &summaries[1].stages);
    assert_eq!((one.workers(), three.workers()), (1, 3));
    assert!(three.wall() <= summaries[1].elapsed && !three.get(RunStage::Lookups).is_zero());
    let report = String::from_utf8(read("3", "report.md")).unwrap();
    assert!(report.contains("| configurations (3 workers at once) |") && report.contains("worker-seconds"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}
