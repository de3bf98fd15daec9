//! `DataSet::from_files` validates an observations.csv as it is read (no
//! row kept as text); it must say exactly what reading the whole file
//! first (`Observations::read`, then `DataSet::from_memory`) says, on good
//! data and on every kind of fault.

use std::path::{Path, PathBuf};

use psdcal::{DataSet, DataSetFiles, LoadOptions, MemoryPoints, PointSource};
use psdcal_io::{Observations, Template};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(name)
}

fn files(observations: &Path) -> DataSetFiles {
    DataSetFiles {
        template: example("template.csv"),
        points: PointSource::Observations(observations.to_path_buf()),
        gains: None,
    }
}

/// Both paths on one file: the same summary, or the same error message.
fn same_answer(observations: &Path, options: &LoadOptions) -> String {
    let whole = Observations::read(observations)
        .map_err(psdcal::Error::from)
        .and_then(|rows| {
            let template = Template::read(example("template.csv")).unwrap();
            DataSet::from_memory(template, MemoryPoints::Observations(rows), options)
        })
        .map(|set| set.summary());
    let streamed = DataSet::from_files(&files(observations), options).map(|set| set.summary());
    match (whole, streamed) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a, b);
            "ok".into()
        }
        (Err(a), Err(b)) => {
            assert_eq!(a.to_string(), b.to_string());
            a.to_string()
        }
        (a, b) => panic!("the two paths disagree: {a:?} versus {b:?}"),
    }
}

/// The example's rows with `edit` applied to the lines after the header.
fn edited(dir: &Path, name: &str, edit: impl Fn(&mut Vec<String>)) -> PathBuf {
    let text = std::fs::read_to_string(example("observations.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    edit(&mut lines);
    let path = dir.join(name);
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path
}

#[test]
fn streamed_check_says_what_the_whole_read_says() {
    let dir = tempfile::tempdir().unwrap();
    let options = LoadOptions::default();
    assert_eq!(same_answer(&example("observations.csv"), &options), "ok");
    let header = |lines: &Vec<String>| lines.iter().position(|l| l.starts_with("image")).unwrap();
    // A point off the 9 × 9 mm area: dropped with a warning (strict: an error).
    let off = edited(dir.path(), "off.csv", |l| {
        let at = header(l) + 3;
        l[at] = "1,3,8.5,0".into();
    });
    assert_eq!(same_answer(&off, &options), "ok");
    let strict = LoadOptions {
        strict: true,
        ..options
    };
    assert_ne!(same_answer(&off, &strict), "ok");
    // An unknown LED after a duplicate: the duplicate, first in file order, is named.
    let both = edited(dir.path(), "both.csv", |l| {
        let at = header(l);
        l[at + 5] = l[at + 2].clone();
        l[at + 20] = "2,99,0,0".into();
    });
    let message = same_answer(&both, &options);
    assert!(message.contains("image '1', LED '2'"), "{message}");
    // An unknown LED alone.
    let unknown = edited(dir.path(), "unknown.csv", |l| {
        let at = header(l);
        l[at + 20] = "2,99,0,0".into();
    });
    assert!(same_answer(&unknown, &options).contains("99"));
    // An image left with too few points; a bad number; an empty file.
    let few = edited(dir.path(), "few.csv", |l| {
        let at = header(l);
        l.truncate(at + 3);
    });
    assert_ne!(same_answer(&few, &options), "ok");
    let bad = edited(dir.path(), "bad.csv", |l| {
        let at = header(l);
        l[at + 4] = "1,4,abc,0".into();
    });
    assert!(same_answer(&bad, &options).contains("abc"));
    let header_only = edited(dir.path(), "header.csv", |l| {
        let at = header(l);
        l.truncate(at + 1);
    });
    assert_ne!(same_answer(&header_only, &options), "ok");
}
