//! The knobs as command-line flags (feature `clap`), built from [`super::KNOBS`]: one flag per
//! knob, whose help gives both presets' values, plus `--preset` and `--check-visibility`.

use anyhow::Result;
use clap::{
    Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches, Parser,
    builder::{PossibleValue, PossibleValuesParser},
};

use super::{Choice, Indirect, KNOBS, Knob, Options, Preset, Values, defaults_text, knob};
use crate::scene::Scene;

/// The render flags: a preset, then each knob given explicitly (which overrides the preset's
/// value), and the visibility check.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Knobs {
    /// The starting point (the hybrid when not given).
    pub preset: Option<Preset>,
    /// The knob flags given, by name ([`Knob::name`]), with their values, in [`KNOBS`] order.
    pub values: Vec<(&'static str, String)>,
    /// Also cast a shadow ray for every map decision and count those it contradicts.
    pub check_visibility: bool,
}

impl Knobs {
    /// The value given for knob `name`, if any.
    pub fn given(&self, name: &str) -> Option<&str> {
        self.values.iter().find(|(n, _)| *n == name).map(|(_, v)| v.as_str())
    }

    /// Gives knob `name` the value `value` (replacing any), as its flag would.
    pub fn set(&mut self, name: &str, value: impl Into<String>) -> Result<()> {
        let k = knob(name).ok_or_else(|| anyhow::anyhow!("no knob is named '{name}'"))?;
        self.values.retain(|(n, _)| *n != k.name);
        self.values.push((k.name, value.into()));
        self.values.sort_by_key(|(n, _)| KNOBS.iter().position(|k| k.name == *n));
        Ok(())
    }

    /// The knobs of render flags, e.g. `["--preset", "hybrid", "--shadow-map-res", "512"]`;
    /// clap's message (naming the flag) on error.
    pub fn from_flags<S: AsRef<str>>(flags: &[S]) -> Result<Knobs> {
        let args = flags.iter().map(|f| f.as_ref().to_string());
        KnobParser::try_parse_from(args)
            .map(|p| p.knobs)
            .map_err(|e| anyhow::anyhow!("{}", e.render().to_string().trim_end()))
    }

    /// The options these flags select for `scene`: a scene with an `[indirect]` table gets its
    /// VPL settings and indirect light (by rays under the reference preset, by maps under the
    /// hybrid one) unless `--indirect` says otherwise; flags override the scene's values.
    pub fn options_for(&self, scene: &Scene) -> Result<Options> {
        let mut k = self.clone();
        if let Some(ind) = scene.indirect {
            let from_scene = [
                ("vpls", Some(ind.vpls.to_string())),
                ("vpl-bounces", Some(ind.bounces.to_string())),
                ("vpl-seed", Some(ind.seed.to_string())),
                ("vpl-clamp", ind.clamp.map(|c| c.to_string())),
            ];
            for (name, v) in from_scene {
                if let Some(v) = v.filter(|_| k.given(name).is_none()) {
                    k.set(name, v)?;
                }
            }
        }
        k.options()
    }

    /// The options these flags select.
    pub fn options(&self) -> Result<Options> {
        let preset = self.preset.unwrap_or_default();
        let mut o = preset.options();
        for (name, v) in &self.values {
            let k = knob(name).ok_or_else(|| anyhow::anyhow!("no knob is named '{name}'"))?;
            (k.set)(&mut o, v).map_err(anyhow::Error::msg)?;
        }
        if self.given("indirect").is_none() {
            o.indirect = match (self.given("vpls"), preset) {
                (Some(_), Preset::Hybrid) => Indirect::Maps,
                (Some(_), Preset::Reference) => Indirect::Rays,
                (None, _) => Indirect::None,
            };
        }
        o.check_visibility = self.check_visibility;
        Ok(o)
    }
}

/// Parses render flags alone (for `hyrt sweep` and `hyrt bench`).
#[derive(Parser, Debug)]
#[command(no_binary_name = true)]
struct KnobParser {
    #[command(flatten)]
    knobs: Knobs,
}

const PRESET: &str = "preset";
const CHECK: &str = "check-visibility";

/// Knob `k`'s flag: its values checked by the knob itself, its help ending with both
/// presets' values.
fn arg(k: &'static Knob) -> Arg {
    let a = Arg::new(k.name).long(k.name).value_name(k.value_name).action(ArgAction::Set).help(format!(
        "{} [{}]",
        k.help,
        defaults_text(k)
    ));
    match k.values {
        Values::Names(names, aliases) => {
            let values = names.iter().map(|n| {
                let old = aliases.iter().filter(|(_, new)| new == n).map(|(old, _)| *old);
                PossibleValue::new(*n).aliases(old)
            });
            a.value_parser(PossibleValuesParser::new(values.collect::<Vec<_>>()))
        }
        _ => a.allow_negative_numbers(true).value_parser(move |s: &str| -> Result<String, String> {
            (k.set)(&mut Options::hybrid(), s).map(|()| s.to_string())
        }),
    }
}

impl Args for Knobs {
    fn augment_args(cmd: Command) -> Command {
        let preset = Arg::new(PRESET)
            .long(PRESET)
            .value_name("PRESET")
            .value_parser(PossibleValuesParser::new(Preset::NAMES))
            .help("`hybrid` (the default): raster visibility + SMeRTS with the measured defaults; `reference`: rays everywhere, the ground truth. Each knob flag then overrides its own value.");
        let check = Arg::new(CHECK).long(CHECK).action(ArgAction::SetTrue).help(
            "Also cast a shadow ray for every map decision and count those it contradicts (wrong-visibility pixels, in the stats; these rays are not counted as frame rays).",
        );
        KNOBS.iter().fold(cmd.arg(preset), |cmd, k| cmd.arg(arg(k))).arg(check)
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for Knobs {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let preset = m.get_one::<String>(PRESET).and_then(|p| Preset::from_name(p));
        let values =
            KNOBS.iter().filter_map(|k| m.get_one::<String>(k.name).map(|v| (k.name, v.clone()))).collect();
        Ok(Self { preset, values, check_visibility: m.get_flag(CHECK) })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

/// Parses `WxH` (e.g. `640x480`) for clap.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WxH, e.g. 640x480, got '{s}'"))?;
    let p =
        |v: &str| v.trim().parse::<u32>().map_err(|_| format!("expected WxH with whole numbers, got '{s}'"));
    Ok((p(w)?, p(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_preset_and_vpls_pick_the_indirect_mode() {
        let k = Knobs::from_flags(&["--preset", "hybrid", "--bias", "2", "--borders", "depth"]).unwrap();
        let o = k.options().unwrap();
        assert_eq!(o.shadow.bias, 2.0);
        assert_eq!(o.shadow.borders, super::super::Borders::MapSpace, "`depth` is the old name");
        assert_eq!(o.visibility, super::super::Visibility::Raster);
        let vpls = |flags: &[&str]| Knobs::from_flags(flags).unwrap().options().unwrap().indirect;
        assert_eq!(vpls(&["--preset", "reference", "--vpls", "4"]), Indirect::Rays);
        assert_eq!(vpls(&["--vpls", "4"]), Indirect::Maps, "the hybrid is the default preset");
        assert_eq!(vpls(&["--preset", "hybrid", "--vpls", "4"]), Indirect::Maps);
        assert_eq!(vpls(&["--preset", "hybrid", "--vpls", "4", "--indirect", "none"]), Indirect::None);
        assert_eq!(vpls(&["--preset", "hybrid"]), Indirect::None);
        assert_eq!(Knobs::default().options().unwrap(), Options::hybrid());
        let e = Knobs::from_flags(&["--bias", "-1"]).unwrap_err().to_string();
        assert!(e.contains("--bias must be a finite number >= 0, got -1"), "{e}");
        let e = Knobs::from_flags(&["--shadow-map-res", "abc"]).unwrap_err().to_string();
        assert!(e.contains("invalid value 'abc'"), "{e}");
    }

    #[test]
    fn the_help_gives_both_presets_values() {
        let cmd = <Knobs as Args>::augment_args(Command::new("t"));
        let help = cmd.clone().render_long_help().to_string();
        assert!(
            help.contains("[reference: 2048; hybrid: 2048]") || help.contains("[default: 2048]"),
            "{help}"
        );
        assert!(help.contains("[reference: rays; hybrid: raster]"), "{help}");
        assert!(help.contains("map-space"), "{help}");
    }
}
