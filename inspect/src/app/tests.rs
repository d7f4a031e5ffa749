//! Unit tests of the window's helpers.

use super::*;

/// Every knob the inspector offers a slider for declares the slider's range, within the
/// values the knob accepts.
#[test]
fn sliders_take_their_ranges_from_the_knobs() {
    let src = include_str!("panels.rs");
    let names: Vec<&str> = src.split("knob_range(\"").skip(1).filter_map(|r| r.split('"').next()).collect();
    assert!(names.len() >= 11, "{names:?}");
    for name in names {
        let k = hyrt::options::knob(name).unwrap_or_else(|| panic!("no knob {name}"));
        let (lo, hi) = k.slider.unwrap_or_else(|| panic!("knob {name} declares no slider range"));
        assert!(lo < hi, "{name}");
        for v in [lo, hi] {
            assert!((k.set)(&mut hyrt::options::Options::hybrid(), &v.to_string()).is_ok(), "{name}: {v}");
        }
    }
}

#[test]
fn times_are_masked() {
    assert_eq!(mask_ms("reused: built once (12.5 ms), 3 lights"), "reused: built once (… ms), 3 lights");
    assert_eq!(mask_ms("1.0 ms and 2 ms, 3 px"), "… ms and … ms, 3 px");
    assert_eq!(mask_ms("no times"), "no times");
}
