//! README.md opens with the two commands a newcomer runs; CI runs exactly
//! the test command it gives.

#[test]
fn ci_runs_the_readme_test_command() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let ci = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/.ci/run")).unwrap();
    let block = readme.split("```").nth(1).expect("README opens with a code block");
    let commands: Vec<&str> =
        block.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#') && *l != "sh").collect();
    assert_eq!(commands.len(), 2, "main job and tests: {commands:?}");
    assert!(commands[0].starts_with("cargo run --release -- experiment"), "{}", commands[0]);
    let test = commands[1];
    assert!(test.starts_with("cargo test"), "{test}");
    assert!(ci.lines().any(|l| l.trim() == test), ".ci/run does not run `{test}`");
}
