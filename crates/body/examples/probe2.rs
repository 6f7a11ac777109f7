use anima_body::*;

fn main() {
    for mode in
        [PdMode::Explicit, PdMode::OdeBrake, PdMode::ImplicitMotor, PdMode::ImplicitSpring, PdMode::StablePd]
    {
        let sk = BuiltinSkeleton::Humanoid.load();
        let sk = sk
            .with_actuation(Actuation { mode, gain_scale: 10.0, torque_limit_rad: 1.0, brake_rad_s: 0.5 })
            .unwrap();
        let mut s = WorldSettings::thesis();
        s.dt = 0.001;
        s.gravity = 0.0;
        s.ground = None;
        let mut w = World::new(s).unwrap();
        let m = w.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
        let knee = sk.actuator_index("knee_l").unwrap();
        let it = sk.actuator_index("inter_thigh").unwrap();
        let c = w.commands_mut(m).unwrap();
        c.push(Signal::angle(knee, 0.5)).unwrap();
        c.push(Signal::angle(it, 0.4)).unwrap();
        let mut sens = Sensors::new(&w, m).unwrap();
        for k in 0..3000 {
            w.step().unwrap();
            if k % 500 == 0 || k == 2999 {
                w.sense(&mut sens).unwrap();
                let mo = w.momentum(m).unwrap();
                println!(
                    "{mode:?} t={:.3} knee {:.4} it {:.4} torque {:.3} {:.3} L {:.2e}",
                    sens.time,
                    sens.actuator_angle[knee],
                    sens.actuator_angle[it],
                    sens.actuator_torque[knee],
                    sens.actuator_torque[it],
                    mo.angular
                );
            }
        }
    }
}
