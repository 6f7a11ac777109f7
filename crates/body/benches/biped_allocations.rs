//! Heap allocations per physics step of the standard biped (`assets/scenes/standard-biped.ron`, issue #19):
//! `cargo bench -p anima-body --bench biped_allocations` prints them for a second of standing after a
//! second of settling. A separate bench from `standard_biped` because the counting allocator it links
//! would slow the timed one.

use allocation_counter::measure;
use anima_body::{BodyScene, Skeleton};

const SKELETON: &str = include_str!("../../../assets/skeletons/standard-biped.ron");
const SCENE: &str = include_str!("../../../assets/scenes/standard-biped.ron");
const STEPS: u64 = 1000;

fn main() {
    let sk = Skeleton::from_ron_str(SKELETON).expect("valid skeleton");
    let scene = BodyScene::from_ron_str(SCENE).expect("valid scene");
    let mut world = scene.build(&[sk]).expect("builds");
    for _ in 0..1000 {
        world.step().expect("stands");
    }
    let info = measure(|| {
        for _ in 0..STEPS {
            world.step().expect("stands");
        }
    });
    let per = |n: u64| n as f64 / STEPS as f64;
    println!(
        "standard biped, {STEPS} steps of 1 ms: {:.1} allocations and {:.0} bytes allocated per step; \
         at most {} allocations ({} bytes) live at once",
        per(info.count_total),
        per(info.bytes_total),
        info.count_max,
        info.bytes_max
    );
}
