//! Physics steps per second for the standard biped of the shared benchmark scenes (`benchmarks.md`):
//! 7 bodies, six hinges under explicit PD (kp = 1000, kd = 10, |τ| ≤ 1000 N·m), feet alone on the
//! ground, Δt = 1 ms, one Rapier sub-step, single-threaded — the scene `assets/scenes/standard-biped.ron`.
//! MuJoCo 4.0 runs it at about 49,000 steps/s on the same machine, PyBullet about 9,700.

use anima_body::{BodyScene, Skeleton};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const SKELETON: &str = include_str!("../../../assets/skeletons/standard-biped.ron");
const SCENE: &str = include_str!("../../../assets/scenes/standard-biped.ron");

fn bench(c: &mut Criterion) {
    let sk = Skeleton::from_ron_str(SKELETON).expect("valid skeleton");
    let scene = BodyScene::from_ron_str(SCENE).expect("valid scene");
    let mut world = scene.build(&[sk]).expect("builds");
    // Settle onto the ground first: a second of simulated time.
    for _ in 0..1000 {
        world.step().expect("stands");
    }
    let mut group = c.benchmark_group("standard_biped");
    group.throughput(Throughput::Elements(1));
    group.bench_function("explicit-pd, 1 ms", |b| b.iter(|| world.step().expect("finite")));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
