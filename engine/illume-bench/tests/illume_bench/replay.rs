//! Scripted edits are applied exactly when the frame time reaches them, identically on a
//! scene, a world and an engine.

use illume_bench::{Replay, Scenario};
use illume_core::Vec3;
use illume_engine::{Engine, read_world};
use illume_scene::Scene;
use std::path::Path;

const SCENARIO: &str = r#"
scene = "builtin:cornell-spot"
width = 8
height = 6
times_s = [0.0, 0.25, 0.4999, 0.5, 0.75]
[[technique]]
name = "reference"
samples = 1
[[edit]]
at_s = 0.5
instance = "sphere"
translation = [0.25, 0.3, -0.125]
"#;

fn sphere(scene: &Scene) -> Vec3 {
    let i = scene
        .instances
        .iter()
        .position(|i| i.name == "sphere")
        .unwrap();
    Vec3::from(scene.instances[i].world_from_object.translation)
}

#[test]
fn edit_moves_the_named_instance_exactly_when_time_reaches_it() {
    let s = Scenario::parse(SCENARIO, Path::new("edit.toml")).unwrap();
    let mut scene = s.load_scene().unwrap();
    let start = sphere(&scene);
    let target = Vec3::new(0.25, 0.3, -0.125);
    assert!((start - target).length() > 0.1);
    let mut replay = Replay::new(&s);
    for t in s.frame_times() {
        let applied = replay.apply_due(&mut scene, t).unwrap();
        scene.set_time(t);
        let expect_moved = t >= 0.5;
        assert_eq!(
            applied == vec![0],
            t == 0.5,
            "applied once, at 0.5 s (t = {t})"
        );
        let p = sphere(&scene);
        if expect_moved {
            assert!((p - target).length() < 1e-6, "t = {t}: {p}");
        } else {
            assert_eq!(p, start, "t = {t}: moved early");
        }
    }
}

#[test]
fn engine_sees_the_edit_at_the_same_frame() {
    let s = Scenario::parse(SCENARIO, Path::new("edit.toml")).unwrap();
    let config = s.technique_config(0).unwrap();
    let mut engine = Engine::new(s.load_scene().unwrap(), &config).unwrap();
    let start = sphere(&read_world(engine.world()).scene);
    let mut replay = Replay::new(&s);
    for t in s.frame_times() {
        replay.apply_due(&mut engine, t).unwrap();
        let out = engine.step(t).unwrap();
        let p = sphere(&read_world(engine.world()).scene);
        if t >= 0.5 {
            assert!(
                (p - Vec3::new(0.25, 0.3, -0.125)).length() < 1e-6,
                "t = {t}"
            );
        } else {
            assert_eq!(p, start, "t = {t}");
            // No animation selected: the scene stays still, nothing changes.
            assert!(out.changes.is_empty(), "t = {t}: {:?}", out.changes);
        }
    }
}

#[test]
fn edit_of_a_missing_instance_names_it_and_the_alternatives() {
    let text = SCENARIO.replace("instance = \"sphere\"", "instance = \"teapot\"");
    let s = Scenario::parse(&text, Path::new("dir/edit.toml")).unwrap();
    // Every edit is replayed and checked when the scene is loaded, before any frame.
    let e = s.load_scene().unwrap_err().to_string();
    assert!(
        e.contains("dir/edit.toml")
            && e.contains("edit[0]")
            && e.contains("teapot")
            && e.contains("tall_box"),
        "{e}"
    );
}
