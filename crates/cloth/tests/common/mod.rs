//! What the cloth crate's test binaries share.

use std::path::Path;

use anima_cloth::oliveira::{OliveiraScene, ShapeDesc};
use anima_geom::{TriangleMesh, read_obj};

/// The Oliveira-format scene `assets/<folder>/<file>` and the meshes it names (beside it).
pub fn load_scene(folder: &str, file: &str) -> (OliveiraScene, Vec<TriangleMesh>) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(folder);
    let scene: OliveiraScene = ron::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap();
    let meshes = scene
        .objects
        .iter()
        .filter_map(|o| match &o.shape {
            ShapeDesc::Mesh { file, .. } => {
                Some(read_obj(std::io::BufReader::new(std::fs::File::open(dir.join(file)).unwrap())).unwrap())
            }
            _ => None,
        })
        .collect();
    (scene, meshes)
}
