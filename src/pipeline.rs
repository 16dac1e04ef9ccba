//! The stage order of a run; the only module that knows it.
//!
//! Place in the flow: the top. `load` reads the scene and the mesh, builds the model and
//! decides the plan; `check` is `load` plus the report.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::mesh::{self, Mesh};
use crate::model::{self, Model};
use crate::plan::{self, Plan};
use crate::scene::{self, Scene};

/// A scene read and validated against its mesh.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub scene: Scene,
    pub mesh: Mesh,
    pub model: Model,
    pub plan: Plan,
}

/// Reads the scene and its mesh (`mesh_override` replaces the scene's `mesh`), builds the
/// model and the plan.
pub fn load(scene_path: &Path, mesh_override: Option<&Path>) -> Result<Loaded> {
    if !scene_path.is_file() {
        return Err(Error::input(
            scene_path,
            "no such scene file: give the path of a .toml scene",
        ));
    }
    let scene = scene::read_scene(scene_path)?;
    let mesh_path: PathBuf = match (mesh_override, &scene.mesh) {
        (Some(m), _) => m.to_path_buf(),
        (None, Some(m)) => m.clone(),
        (None, None) => {
            return Err(Error::input(
                scene_path,
                "no mesh: add mesh = \"FILE.msh\" to the scene or pass --mesh FILE.msh",
            ))
        }
    };
    if !mesh_path.is_file() {
        return Err(Error::input(
            &mesh_path,
            "no such mesh file: mesh the .geo first (make mesh, or gmsh -2 -format msh41 FILE.geo)",
        ));
    }
    let mesh = mesh::read_msh(&mesh_path)?;
    let model = model::build(&scene, &mesh, &mesh_path)?;
    let plan = plan::plan(&scene, &model)?;
    Ok(Loaded {
        scene,
        mesh,
        model,
        plan,
    })
}
