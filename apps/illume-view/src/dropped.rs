//! Files dropped on the window: loaded off the window's thread, then handed to the render
//! thread as the new scene ([`Command::Scene`]); a file that cannot be loaded (unknown
//! format, malformed, missing, or a loader that panics) is reported in the window's
//! messages and the current scene stays.

use crate::renderer::Command;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// Messages shown at the bottom of the window's panel (errors never crash the window),
/// shared with the threads that report them.
#[derive(Clone, Default)]
pub struct Messages(Arc<Mutex<Vec<String>>>);

impl Messages {
    /// The most messages kept.
    const KEPT: usize = 6;

    /// Adds a message (also logged at info: the CLI prints it on stderr).
    pub fn push(&self, m: String) {
        log::info!("illume view: {m}");
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner());
        v.push(m);
        if v.len() > Self::KEPT {
            v.remove(0);
        }
    }

    /// The messages, oldest first.
    pub fn all(&self) -> Vec<String> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Loads `path` on a new thread; sends the scene to the render thread through
/// `commands`, or pushes the error to `messages`. The handle is for tests to wait on.
pub fn open_dropped(
    path: PathBuf,
    commands: Sender<Command>,
    messages: Messages,
) -> JoinHandle<()> {
    std::thread::spawn(move || match load(&path) {
        Ok(scene) => {
            for w in &scene.warnings {
                messages.push(format!("{}: {w}", path.display()));
            }
            if commands.send(Command::Scene(Box::new(scene))).is_err() {
                messages.push(format!("{}: the renderer has stopped", path.display()));
            }
        }
        Err(e) => messages.push(format!("cannot open {}: {e}", path.display())),
    })
}

/// The scene in `path`, as `illume view PATH` loads it; a loader panic, a scene without
/// geometry and one that fails validation are errors.
fn load(path: &Path) -> Result<illume_scene::Scene, String> {
    let options = illume_scene::LoadOptions::default();
    let loaded = std::panic::catch_unwind(|| illume_scene::load_scene_with(path, &options));
    match loaded {
        // What the engine would refuse is refused here, before the running scene goes.
        Ok(Ok(scene))
            if scene
                .instances
                .iter()
                .all(|i| scene.meshes[i.mesh.index()].triangle_count() == 0) =>
        {
            Err("the file has no triangles".into())
        }
        Ok(Ok(scene)) => scene.validate().map(|()| scene).map_err(|e| e.to_string()),
        Ok(Err(e)) => Err(e.to_string()),
        Err(_) => Err("the loader failed (a bug: please report the file)".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::renderer::tests::{small_render_thread, wait_for};
    use illume_engine::TechniqueKind;
    use std::sync::mpsc::channel;

    fn temp_file(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("illume-view-drop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn a_bad_file_is_a_message_and_no_scene() {
        let (tx, rx) = channel();
        let messages = Messages::default();
        let files = [
            temp_file(
                "broken.gltf",
                b"{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ {",
            ),
            temp_file("notes.txt", b"not a scene"),
            temp_file("empty.obj", b""),
            std::env::temp_dir().join("illume-view-no-such-file.ply"),
        ];
        for f in &files {
            open_dropped(f.clone(), tx.clone(), messages.clone())
                .join()
                .expect("the loading thread does not panic");
        }
        if let Ok(Command::Scene(scene)) = rx.try_recv() {
            panic!("{} replaced the scene", scene.source);
        }
        let all = messages.all();
        for f in &files {
            let name = f.file_name().unwrap().to_str().unwrap();
            assert!(
                all.iter()
                    .any(|m| m.starts_with("cannot open") && m.contains(name)),
                "no message names {name}: {all:?}"
            );
        }
    }

    /// A dropped scene replaces the running one: the render thread renders it; a bad
    /// file dropped next leaves it running with a message.
    #[test]
    fn a_dropped_scene_is_rendered_and_a_bad_one_is_reported() {
        let render = small_render_thread(TechniqueKind::Reference);
        let wait =
            |what: &str, f: &dyn Fn(&crate::renderer::Shown) -> bool| wait_for(&render, what, f);
        let first = wait("a first frame", &|_| true);
        let obj = illume_scene::shared_scenes_dir().join("cornell_box/CornellBox-Original.obj");
        let expected = illume_scene::load_scene_with(&obj, &Default::default()).unwrap();
        let messages = Messages::default();
        open_dropped(obj, render.commands.clone(), messages.clone())
            .join()
            .unwrap();
        let dropped = wait("a frame of the dropped scene", &|s| {
            s.materials.len() == expected.materials.len()
                && s.scene_camera == expected.camera.world_from_camera
        });
        assert_ne!(first.scene_camera, dropped.scene_camera);
        assert!(
            dropped.image.mean().length() > 0.0,
            "the dropped scene is black"
        );
        let bad = temp_file("bad.glb", b"glTF garbage");
        open_dropped(bad, render.commands.clone(), messages.clone())
            .join()
            .unwrap();
        assert!(
            messages.all().iter().any(|m| m.contains("bad.glb")),
            "{:?}",
            messages.all()
        );
        // The renderer still runs the dropped scene.
        let index = dropped.index;
        render.send(Command::Reference(true));
        let later = wait("a later frame", &|s| s.index > index);
        assert_eq!(later.scene_camera, dropped.scene_camera);
    }
}
