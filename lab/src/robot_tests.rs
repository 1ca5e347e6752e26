use super::*;
use planner_core::execute::schedule::schedule;
use planner_core::{plan, Scenario};

fn round_trip_command(c: RobotCommand) {
    let text = c.to_string();
    let back: RobotCommand = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
    assert_eq!(back, c, "{text}");
    if let (RobotCommand::Step(a), RobotCommand::Step(b)) = (c, back) {
        assert_eq!(a.duration_s.to_bits(), b.duration_s.to_bits(), "{text}");
    }
}

#[test]
fn every_step_of_a_plan_crosses_the_link_bit_for_bit() {
    let scenario = Scenario::paper();
    let best = plan(&scenario).unwrap().best().unwrap().clone();
    let s = schedule(&scenario, &best).unwrap();
    let list = step_list(&s.steps);
    assert_eq!(
        list[0],
        RobotCommand::Steps {
            count: s.steps.len()
        }
    );
    for c in list {
        round_trip_command(c);
    }
}

#[test]
fn each_step_kind_and_word_round_trips() {
    let awkward = [0.1_f32, 1.0 / 3.0, 1e-7, 123_456.79, 0.0, f32::MIN_POSITIVE];
    for v in awkward {
        for op in [
            Op::Insert { length_mm: v },
            Op::Rotate { angle_deg: -v },
            Op::InsertSpin {
                length_mm: v,
                turns: 4,
            },
            Op::InsertDuty {
                length_mm: v,
                duty: 0.25,
            },
        ] {
            round_trip_command(RobotCommand::Step(Step {
                op,
                duration_s: v * 2.0,
            }));
        }
    }
    for c in [
        RobotCommand::Posture {
            theta1_deg: 28.7,
            theta2_deg: -1.0 / 3.0,
            roll_deg: 180.0,
        },
        RobotCommand::Go,
        RobotCommand::Hold,
        RobotCommand::Stop,
        RobotCommand::Steps { count: MAX_STEPS },
    ] {
        round_trip_command(c);
    }
    for r in [
        RobotReport::Progress {
            piece: 17,
            depth_mm: 1.0 / 3.0,
            base_deg: -540.25,
        },
        RobotReport::PostureSet {
            depth_mm: 0.0,
            base_deg: 540.0 + f64::from(1.0_f32 / 3.0),
        },
        RobotReport::PostureRefused { max_tilt_deg: 0.0 },
        RobotReport::Done,
        RobotReport::Holding,
        RobotReport::Stopped,
        RobotReport::Collided { depth_mm: 41.25 },
    ] {
        assert_eq!(r.to_string().parse::<RobotReport>(), Ok(r));
    }
}

#[test]
fn the_grammar_reads_as_documented() {
    assert_eq!(
        "insert length_mm=10 speed_mm_s=2".parse::<RobotCommand>(),
        Ok(RobotCommand::Step(Step {
            op: Op::Insert { length_mm: 10.0 },
            duration_s: 5.0
        }))
    );
    assert_eq!(
        "rotate angle_deg=-180 duration_s=1".parse::<RobotCommand>(),
        Ok(RobotCommand::Step(Step {
            op: Op::Rotate { angle_deg: -180.0 },
            duration_s: 1.0
        }))
    );
    assert_eq!(
        RobotCommand::Step(Step {
            op: Op::InsertDuty {
                length_mm: 8.0,
                duty: 0.5
            },
            duration_s: 4.0
        })
        .to_string(),
        "duty-insert length_mm=8 duty=0.5 duration_s=4 speed_mm_s=2"
    );
}

#[test]
fn bad_strings_are_typed_errors() {
    let cases: [(&str, GrammarError); 9] = [
        ("", GrammarError::Empty),
        ("   ", GrammarError::Empty),
        ("jump", GrammarError::UnknownWord("jump".into())),
        ("go now", GrammarError::NotKeyValue("now".into())),
        ("insert length_mm=1", GrammarError::MissingKey("speed_mm_s")),
        ("insert speed_mm_s=1", GrammarError::MissingKey("length_mm")),
        (
            "insert length_mm=1 length_mm=2 duration_s=1",
            GrammarError::UnknownKey("length_mm".into()),
        ),
        (
            "rotate angle_deg=NaN duration_s=1",
            GrammarError::BadNumber {
                key: "angle_deg".into(),
                value: "NaN".into(),
            },
        ),
        (
            "duty-insert length_mm=1 duty=1.5 duration_s=1",
            GrammarError::BadNumber {
                key: "duty".into(),
                value: "1.5".into(),
            },
        ),
    ];
    for (text, want) in cases {
        assert_eq!(text.parse::<RobotCommand>(), Err(want), "{text}");
    }
    assert!("insert length_mm=-1 duration_s=1"
        .parse::<RobotCommand>()
        .is_err());
    assert!("insert length_mm=1 speed_mm_s=0"
        .parse::<RobotCommand>()
        .is_err());
    assert!("steps count=-2".parse::<RobotCommand>().is_err());
    let too_many = format!("steps count={}", MAX_STEPS + 1);
    assert!(too_many.parse::<RobotCommand>().is_err());
    assert!("steps count=99999999999".parse::<RobotCommand>().is_err());
    assert!("progress piece=1 depth_mm=inf base_deg=0"
        .parse::<RobotReport>()
        .is_err());
    assert!("progress piece=1 depth_mm=2"
        .parse::<RobotReport>()
        .is_err());
    assert!("stopped now=1".parse::<RobotReport>().is_err());
    assert!(
        "collided".parse::<RobotReport>().is_err(),
        "the depth is required"
    );
}

/// The absolute roll is read as an `f64`: a rotation's `f32` bits survive a large roll added to
/// it and taken off again.
#[test]
fn a_large_absolute_roll_keeps_the_rotations_bits() {
    let turned = 1.0_f32 / 3.0;
    let report = RobotReport::Progress {
        piece: 3,
        depth_mm: 2.0,
        base_deg: 900.0 + f64::from(turned),
    };
    let Ok(RobotReport::Progress { base_deg, .. }) = report.to_string().parse() else {
        panic!("{report}");
    };
    assert_eq!(((base_deg - 900.0) as f32).to_bits(), turned.to_bits());
    assert_eq!(tilt_deg(0.0, 0.0), 0.0);
    assert!((tilt_deg(30.0, 0.0) - 30.0).abs() < 1e-4);
    assert!((tilt_deg(-20.0, 20.0) - 27.990_9).abs() < 1e-3);
}
