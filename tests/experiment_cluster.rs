//! Sharded runs and `lixel merge` (issue 22), driven by the commands of
//! `docs/cluster.md`: the Slurm array script and the Kubernetes Indexed Job
//! manifest are parsed, their `lixel experiment` command lines run locally
//! as shards of a tiny run (the scheduler's variables set by hand), and the
//! merged CSVs must equal an unsharded run's byte for byte. Then the merge's
//! refusals: a missing shard, a shard given twice, a shard of another run.
#![cfg(feature = "render")]

#[path = "render_common/mod.rs"]
mod render_common;

use std::path::{Path, PathBuf};
use std::process::Command;

const DOC: &str = include_str!("../docs/cluster.md");

/// Replaces the paper preset with a tiny run (seconds) of the same shape.
const TINY: [&str; 16] = [
    "--configs",
    "5",
    "--screen",
    "64",
    "--map",
    "64",
    "--triangles",
    "2000",
    "--methods",
    "normal,focused,optimized",
    "--truth",
    "raytrace",
    "--equivalence",
    "1",
    "--seed",
    "11",
];

/// The fenced code blocks of `lang` in the page.
fn blocks(lang: &str) -> Vec<String> {
    let fence = format!("```{lang}\n");
    DOC.split(fence.as_str()).skip(1).map(|b| b.split("```").next().unwrap_or_default().to_string()).collect()
}

/// The Slurm script: its array size and its `lixel experiment` arguments.
fn slurm() -> (usize, Vec<String>) {
    let script = blocks("bash").into_iter().find(|b| b.contains("#SBATCH --array")).expect("a Slurm script");
    let array = script.lines().find_map(|l| l.strip_prefix("#SBATCH --array=")).expect("#SBATCH --array");
    let (lo, hi) = array.trim().split_once('-').expect("--array=LO-HI");
    let tasks = hi.parse::<usize>().unwrap() - lo.parse::<usize>().unwrap() + 1;
    let line = script.lines().find(|l| l.contains("lixel experiment")).expect("a lixel experiment line");
    let args: Vec<String> = line.split_whitespace().skip_while(|w| *w != "lixel").skip(1).map(String::from).collect();
    (tasks, args)
}

/// The Indexed Job: its completions and the container's command.
fn kubernetes() -> (usize, Vec<String>) {
    let manifest = blocks("yaml").into_iter().find(|b| b.contains("kind: Job")).expect("a Job manifest");
    assert!(manifest.contains("completionMode: Indexed"), "not an Indexed Job");
    let field = |name: &str| -> String {
        let line = manifest.lines().find(|l| l.trim_start().starts_with(name)).unwrap_or_else(|| panic!("no {name}"));
        line.trim_start()[name.len()..].trim().to_string()
    };
    let completions: usize = field("completions:").parse().unwrap();
    assert_eq!(field("parallelism:").parse::<usize>().unwrap(), completions);
    // A YAML flow list of double-quoted strings is JSON.
    let command: Vec<String> = serde_json::from_str(&field("command:")).expect("command as a JSON-style list");
    assert_eq!(command[0], "lixel");
    (completions, command[1..].to_vec())
}

/// `args` with the paper preset made tiny and `--out` (and `--shard-count`,
/// when given) replaced.
fn localize(args: &[String], out: &Path, shard_count: Option<usize>) -> Vec<String> {
    let mut v = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--preset" => {
                assert_eq!(it.next().map(String::as_str), Some("paper"), "the page runs the paper preset");
                v.extend(["--preset", "quick"].map(String::from));
            }
            "--out" => {
                it.next();
                v.extend(["--out".to_string(), out.to_string_lossy().into_owned()]);
            }
            "--shard-count" => {
                it.next();
                v.extend(["--shard-count".to_string(), shard_count.expect("a count").to_string()]);
            }
            _ => v.push(a.clone()),
        }
    }
    v.extend(TINY.map(String::from));
    v
}

fn lixel(args: &[String], env: &[(&str, String)]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_lixel"))
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_MIN")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .env_remove("JOB_COMPLETION_INDEX")
        .envs(env.iter().map(|(k, v)| (*k, v.as_str())))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "lixel {args:?} failed: {stderr}");
    stderr
}

fn merge(dirs: &[PathBuf], out: &Path, extra: &[&str]) -> (bool, String) {
    let mut args = vec!["merge".to_string()];
    args.extend(dirs.iter().map(|d| d.to_string_lossy().into_owned()));
    args.extend(["--out".to_string(), out.to_string_lossy().into_owned()]);
    args.extend(extra.iter().map(|s| (*s).to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_lixel")).args(&args).output().unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn shards(dir: &Path, n: usize) -> Vec<PathBuf> {
    (0..n).map(|i| dir.join(format!("shard-{i}-of-{n}"))).collect()
}

fn same_csvs(a: &Path, b: &Path) {
    for f in ["configs.csv", "summary.csv"] {
        let (x, y) = (std::fs::read(a.join(f)).unwrap(), std::fs::read(b.join(f)).unwrap());
        assert!(x == y, "{f} differs between {} and {}", a.display(), b.display());
    }
}

#[test]
fn the_cluster_page_is_a_slurm_array_and_an_indexed_job_of_twenty_shards() {
    let (tasks, args) = slurm();
    assert_eq!(tasks, 20);
    assert!(args.windows(2).any(|w| w == ["--shard", "env"]), "{args:?}");
    let (completions, command) = kubernetes();
    assert_eq!(completions, 20);
    assert!(command.windows(2).any(|w| w == ["--shard-count", "20"]), "{command:?}");
    assert!(DOC.contains("lixel merge results/paper/shard-*-of-20 --out results/paper/merged"));
}

#[test]
fn shards_from_the_cluster_page_merge_into_the_unsharded_report() {
    let Some(_) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-cluster-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let n = 3;

    // One run, unsharded: the Slurm command line without its shard.
    let (_, slurm_args) = slurm();
    let whole = dir.join("whole");
    let unsharded: Vec<String> =
        localize(&slurm_args, &whole, None).into_iter().filter(|a| a != "--shard" && a != "env").collect();
    lixel(&unsharded, &[]);

    // The Slurm array, task ids 1..=n as with --array=1-N.
    let slurm_out = dir.join("slurm");
    for id in 1..=n {
        let env = [
            ("SLURM_ARRAY_TASK_ID", id.to_string()),
            ("SLURM_ARRAY_TASK_MIN", "1".to_string()),
            ("SLURM_ARRAY_TASK_COUNT", n.to_string()),
        ];
        lixel(&localize(&slurm_args, &slurm_out, None), &env);
    }
    let merged = dir.join("slurm-merged");
    let (ok, e) = merge(&shards(&slurm_out, n), &merged, &[]);
    assert!(ok, "{e}");
    same_csvs(&whole, &merged);
    let report = std::fs::read_to_string(merged.join("report.md")).unwrap();
    assert!(report.contains("Merged from 3 shard directories") && !report.contains("PARTIAL"), "{report}");

    // The Indexed Job.
    let (_, command) = kubernetes();
    let k8s_out = dir.join("k8s");
    for index in 0..n {
        lixel(&localize(&command, &k8s_out, Some(n)), &[("JOB_COMPLETION_INDEX", index.to_string())]);
    }
    let (ok, e) = merge(&shards(&k8s_out, n), &dir.join("k8s-merged"), &[]);
    assert!(ok, "{e}");
    same_csvs(&whole, &dir.join("k8s-merged"));

    // A missing shard is named (shard 2 of 3 holds configuration 2), then
    // accepted with --allow-missing and marked.
    let two = &shards(&slurm_out, n)[..2];
    let (ok, e) = merge(two, &dir.join("partial"), &[]);
    assert!(!ok && e.contains("missing configurations 2"), "{e}");
    let (ok, e) = merge(two, &dir.join("partial"), &["--allow-missing"]);
    assert!(ok, "{e}");
    let partial = std::fs::read_to_string(dir.join("partial").join("report.md")).unwrap();
    assert!(partial.contains("PARTIAL REPORT: 1 of 5 configurations are missing (2)"), "{partial}");

    // A shard given twice, a shard of another run, an existing report.
    let mut twice = shards(&slurm_out, n);
    twice.push(twice[0].clone());
    let (ok, e) = merge(&twice, &dir.join("twice"), &[]);
    assert!(!ok && e.contains("in more than one directory 0, 3"), "{e}");
    let other = dir.join("other");
    let mut reseeded = localize(&slurm_args, &other, None);
    let seed = reseeded.iter().position(|a| a == "--seed").unwrap();
    reseeded[seed + 1] = "12".into();
    lixel(&reseeded, &[("SLURM_ARRAY_TASK_ID", "2".into()), ("SLURM_ARRAY_TASK_COUNT", n.to_string())]);
    let mut mixed = shards(&slurm_out, n)[..2].to_vec();
    mixed.push(shards(&other, n)[2].clone());
    let (ok, e) = merge(&mixed, &dir.join("mixed"), &[]);
    assert!(!ok && e.contains("seed (--seed) differs: recorded 12, now 11"), "{e}");
    let (ok, e) = merge(&shards(&slurm_out, n), &merged, &[]);
    assert!(!ok && e.contains("already holds a report"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
