//! Every input a fuzzer found a bug with (`tests/data/fuzz/TARGET/`, minimised)
//! replayed through the same target body and oracle as `fuzz/run` uses: it
//! must load or fail with one line, and what loads must render finite pixels
//! and answer every ray query as brute force does.

#[allow(dead_code)]
#[path = "../fuzz/src/lib.rs"]
mod oracle;

use std::path::Path;

#[test]
fn fuzz_findings_stay_fixed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let mut replayed = 0;
    for dir in std::fs::read_dir(&root).expect("tests/data/fuzz") {
        let dir = dir.unwrap().path();
        let target = dir.file_name().unwrap().to_str().unwrap().to_string();
        let run = oracle::targets::by_name(&target)
            .unwrap_or_else(|| panic!("{}: no fuzz target of that name", dir.display()));
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|f| f.unwrap().path())
            .collect();
        files.sort();
        for file in files {
            let bytes = std::fs::read(&file).unwrap();
            let outcome = std::panic::catch_unwind(|| run(&bytes));
            assert!(
                outcome.is_ok(),
                "{}: the {target} target fails again",
                file.display()
            );
            replayed += 1;
        }
    }
    assert!(
        replayed > 0,
        "no findings to replay under {}",
        root.display()
    );
}
