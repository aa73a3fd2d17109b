//! The whole study on a tiny set: consistent rows, IPC at round-off, SBR coarse but close,
//! deterministic apart from the times, and every output file written.

use bt_study::report::{self, CSV_HEADER};
use bt_study::{StudyConfig, StudySolver, run};

fn tiny() -> StudyConfig {
    StudyConfig {
        rooms: 4,
        steps: 2,
        seed: 11,
        sbr_step_deg: 2.0,
        ..StudyConfig::default()
    }
}

#[test]
fn room_steps_beyond_the_budget_are_refused_before_any_room() {
    let config = StudyConfig {
        rooms: usize::MAX,
        steps: usize::MAX,
        ..tiny()
    };
    let e = run(&config, &mut |_, _| panic!("no room may run"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("more than 1.8e19 room-steps"), "{e}");
    assert!(e.contains("--max-room-steps"), "{e}");
    let config = StudyConfig {
        max_room_steps: 7,
        ..tiny()
    };
    let e = run(&config, &mut |_, _| {}).unwrap_err().to_string();
    assert!(e.contains("8 room-steps, more than the budget of 7"), "{e}");
}

#[test]
fn tiny_study_is_consistent() {
    let mut calls = 0;
    let results = run(&tiny(), &mut |done, total| {
        calls += 1;
        assert!(done <= total && total == 8);
    })
    .unwrap();
    assert_eq!(calls, 8);
    assert_eq!(results.rows.len(), 4 * 2 * 4);
    let csv = report::csv(&results);
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    let columns = CSV_HEADER.split(',').count();
    let mut sbr_error = 0.0;
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), columns, "{line}");
        for cell in &cells[10..] {
            let x: f64 = cell.parse().unwrap();
            assert!(x.is_finite() && x >= 0.0, "{line}");
        }
        let err_tx: f64 = cells[10].parse().unwrap();
        let err_rx: f64 = cells[12].parse().unwrap();
        let (missed, spurious): (usize, usize) =
            (cells[8].parse().unwrap(), cells[9].parse().unwrap());
        match cells[5] {
            "image" => assert!(err_tx == 0.0 && err_rx == 0.0 && missed == 0 && spurious == 0),
            "ipc-gauss-seidel" | "ipc-jacobi" => {
                assert!(err_tx < 1e-6 && err_rx < 1e-6, "{line}");
                assert_eq!((missed, spurious), (0, 0), "{line}");
            }
            "sbr" => {
                assert!(err_tx > 0.0 && err_tx < 2.0, "{line}");
                sbr_error += err_tx;
            }
            other => panic!("unknown solver {other}"),
        }
    }
    assert!(sbr_error > 0.0);
    // Every room has paths, and SBR with a 2° step finds most of them.
    for r in results
        .rows
        .iter()
        .filter(|r| r.comparison.solver == StudySolver::Sbr)
    {
        let image = results
            .rows
            .iter()
            .find(|i| {
                i.comparison.solver == StudySolver::Image && i.room == r.room && i.step == r.step
            })
            .map(|i| &i.comparison)
            .unwrap();
        assert!(image.paths > 0);
        assert!(
            r.comparison.missed * 4 <= image.paths,
            "{r:?} vs {} exact paths",
            image.paths
        );
    }
    let summary = report::summary(&results);
    assert!(summary.contains("Seed 11") && summary.contains("SBR time / IPC"));
}

#[test]
fn results_are_deterministic_apart_from_times() {
    let strip = |mut r: bt_study::StudyResults| {
        r.rows
            .iter_mut()
            .for_each(|row| row.comparison.time_s = 0.0);
        report::csv(&r)
    };
    let config = StudyConfig {
        rooms: 2,
        steps: 2,
        ..tiny()
    };
    let a = strip(run(&config, &mut |_, _| {}).unwrap());
    let b = strip(run(&config, &mut |_, _| {}).unwrap());
    assert_eq!(a, b);
}

#[test]
fn outputs_are_written() {
    let config = StudyConfig {
        rooms: 2,
        steps: 2,
        sbr_step_deg: 4.0,
        ..tiny()
    };
    let results = run(&config, &mut |_, _| {}).unwrap();
    let dir = std::env::temp_dir().join(format!("bt-study-test-{}", std::process::id()));
    let files = bt_study::io::write_outputs(&dir, &results).unwrap().files;
    for name in [
        "results.csv",
        "summary.md",
        "fig5-rooms.svg",
        "fig5-rooms.png",
        "fig6-angular-error.svg",
        "fig6-angular-error.png",
        "fig7-elapsed-time.svg",
        "fig7-elapsed-time.png",
    ] {
        let path = dir.join(name);
        assert!(files.contains(&path), "{name} not reported");
        assert!(
            std::fs::metadata(&path).unwrap().len() > 100,
            "{name} is empty"
        );
    }
    let png = std::fs::read(dir.join("fig6-angular-error.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn invalid_settings_are_reported() {
    let config = StudyConfig {
        rooms: 0,
        sbr_step_deg: -1.0,
        ..tiny()
    };
    let e = run(&config, &mut |_, _| {}).unwrap_err().to_string();
    assert!(e.contains("rooms") && e.contains("sbr step"), "{e}");
}

#[test]
fn the_candidate_budget_stops_the_study() {
    let config = StudyConfig {
        rooms: 1,
        steps: 1,
        max_candidates: 3,
        ..tiny()
    };
    let e = run(&config, &mut |_, _| {}).unwrap_err().to_string();
    assert!(
        e.contains("room-0-step-0") && e.contains("--max-candidates"),
        "{e}"
    );
}
