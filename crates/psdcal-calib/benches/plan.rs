//! Planning time: 1 500 candidates of the 14-LED template on lens 2 at
//! 40 dB, N = 9 and N = 20 poses (greedy and exchange), without and with
//! the channel gains freed.

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal_calib::plan::{plan, PlanOptions, PlanSetup};
use psdcal_calib::RefineOptions;
use psdcal_model::{ChannelGains, CostKind, Model, PsdGeometry, SensorModel};

fn bench(c: &mut Criterion) {
    let setup = PlanSetup {
        model: Model::standard(&SensorModel::paper_lens2()),
        template: psdcal_model::paper_setup::scatter14(),
        geometry: PsdGeometry::default(),
        free: RefineOptions::default().free_names(),
        cost: CostKind::Template,
        relative_noise: 1e-3,
    };
    let lens = SensorModel::paper_lens2();
    let with_gains = PlanSetup {
        model: Model::standard_with_gains(&lens, PsdGeometry::default(), &ChannelGains::UNIT),
        free: RefineOptions {
            fit_gains: true,
            ..RefineOptions::default()
        }
        .free_names(),
        ..setup.clone()
    };
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    for (name, setup) in [("", &setup), ("_gains", &with_gains)] {
        for n in [9usize, 20] {
            let options = PlanOptions {
                images: n,
                ..PlanOptions::default()
            };
            group.bench_function(format!("{n}_of_1500{name}"), |b| {
                b.iter(|| plan(setup, &options).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
