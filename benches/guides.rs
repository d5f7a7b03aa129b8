//! Production scale through guides: the full-head perm (`grooms/recipes/perm_full_head.toml`)
//! on a generated 100,000 × 32 head, simulated on guides and interpolated to every strand, end
//! to end (generate, style, interpolate, export USD). Prints wall seconds per phase and the peak
//! resident memory. One run per configuration by default (each takes minutes on 2 cores);
//! `COIF_BENCH_RUNS=3` for medians. `cargo bench --bench guides [-- FILTER]`.
//!
//! `cargo bench --bench guides -- children` measures instead how children look beside their
//! guides on small curly, wavy and straight heads (see [`children`]).
mod common;
use common::median;
use std::path::Path;
use std::time::Instant;

use coif::generate::{generate, GenerateParams};
use coif::style::{recipe, style, StyleOptions};

struct Config {
    name: &'static str,
    strands: usize,
    guides: usize,
}

const CONFIGS: [Config; 3] = [
    Config { name: "perm-20000x32-from-1000", strands: 20_000, guides: 1_000 },
    Config { name: "perm-100000x32-from-2000", strands: 100_000, guides: 2_000 },
    Config { name: "perm-100000x32-from-5000", strands: 100_000, guides: 5_000 },
];

/// Peak resident memory of this process so far, MB (Linux), if known.
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn main() {
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    if filter.as_deref() == Some("children") {
        return children::run();
    }
    let runs: usize = std::env::var("COIF_BENCH_RUNS").ok().and_then(|r| r.parse().ok()).unwrap_or(1);
    let mut recipe = recipe::load(Path::new("grooms/recipes/perm_full_head.toml")).unwrap();
    let out = tempfile::tempdir().unwrap();
    for config in CONFIGS.iter().filter(|c| filter.as_deref().is_none_or(|f| c.name.contains(f))) {
        recipe.guides = Some(coif::guides::GuideSpec { count: Some(config.guides), ..Default::default() });
        let (mut styling, mut totals) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            let start = Instant::now();
            let groom = generate(&GenerateParams {
                strands: config.strands,
                vertices_per_strand: 32,
                length: 0.24,
                seed: 21,
                ..GenerateParams::default()
            })
            .unwrap();
            let styled_at = Instant::now();
            let styled = style(&groom, &recipe, &StyleOptions::default()).unwrap();
            styling.push(styled_at.elapsed().as_secs_f64());
            coif::io::write_groom(&out.path().join("permed.usda"), &styled.groom).unwrap();
            totals.push(start.elapsed().as_secs_f64());
        }
        println!(
            "{:<28} style+interpolate {:>7.1} s   end to end {:>7.1} s   peak memory {:>6.0} MB   ({} run(s))",
            config.name,
            median(styling),
            median(totals),
            peak_rss_mb().unwrap_or(f64::NAN),
            runs
        );
    }
}

/// Children beside their guides on small generated heads (curly, wavy, straight): styled through
/// guides, and a control where every strand is simulated (what children should look like).
/// Per head and preset it prints, for the guided run and the control:
/// - curl: the children's median curl radius over the guides' (the rods' part of each strand,
///   from 40 % of its length to the tip, as `tests/guides.rs` measures it), as a % difference;
/// - no-collapse: the mean distance at mid-length between each child and its nearest (by root)
///   child of the same first guide, styled over unstyled (issue 16 asks ≥ 0.5);
/// - seam: the mean distance at mid-length between each child and its nearest (by root) child,
///   over pairs bound to different first guides, divided by the same over pairs bound to the
///   same one (1 = no seam where the guides change);
/// - opposite: the share of those nearest pairs whose curls turn opposite ways (the sign of the
///   summed torsion, from 40 % of the length to the tip);
/// - the largest change of a child's length, and child vertices inside the head.
///
/// The control uses the guided run's guide flags and bindings. `COIF_BENCH_CONTROL=0` skips it.
mod children {
    use std::path::Path;

    use coif::analysis::curl_radius;
    use coif::generate::{generate, GenerateParams, Style};
    use coif::groom::Groom;
    use coif::guides::CLOSEST_GUIDES;
    use coif::head::Head;
    use coif::style::{recipe, style, StyleOptions};

    const STRANDS: usize = 300;
    const GUIDES: usize = 30;

    pub fn run() {
        let control = std::env::var("COIF_BENCH_CONTROL").map_or(true, |v| v != "0");
        let heads = [
            ("curly", Style::Curly { radius: 0.01, pitch: 0.03 }),
            ("wavy", Style::Wavy { amplitude: 0.008, wavelength: 0.06 }),
            ("straight", Style::Straight),
        ];
        let presets = std::env::var("COIF_BENCH_PRESETS").unwrap_or("perm_full_head,water_set".into());
        for preset in presets.split(',') {
            let path = format!("grooms/recipes/{preset}.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            let guided =
                recipe::parse(&format!("{text}\n[guides]\ncount = {GUIDES}\n"), Path::new(&path)).unwrap();
            let full = recipe::parse(&text, Path::new(&path)).unwrap();
            for (name, style_kind) in heads {
                let unstyled = generate(&GenerateParams {
                    strands: STRANDS,
                    vertices_per_strand: 32,
                    length: 0.30,
                    seed: 21,
                    style: style_kind,
                    ..GenerateParams::default()
                })
                .unwrap();
                let styled = style(&unstyled, &guided, &StyleOptions::default()).unwrap().groom;
                let flags = styled.guides.clone().unwrap();
                let closest: Vec<u32> = styled
                    .attribute(CLOSEST_GUIDES)
                    .unwrap()
                    .floats()
                    .iter()
                    .step_by(3)
                    .map(|&g| g as u32)
                    .collect();
                let line = |what: &str, groom: &Groom| {
                    let m = Measures::of(&unstyled, groom, &flags, &closest);
                    println!(
                        "{preset:<15} {name:<9} {what:<8} curl {:+6.1} % (guides {:.2} cm)   no-collapse {:.2}   \
                         seam {:.2}   opposite {:2.0} %   length change {:.2} %   inside head {}",
                        100.0 * (m.children_curl / m.guides_curl - 1.0),
                        100.0 * m.guides_curl,
                        m.no_collapse,
                        m.seam,
                        100.0 * m.opposite,
                        100.0 * m.stretch,
                        m.inside
                    );
                };
                line("guided", &styled);
                if control {
                    line("control", &style(&unstyled, &full, &StyleOptions::default()).unwrap().groom);
                }
            }
        }
    }

    struct Measures {
        guides_curl: f32,
        children_curl: f32,
        no_collapse: f32,
        seam: f32,
        opposite: f32,
        stretch: f32,
        inside: usize,
    }

    fn median(mut values: Vec<f32>) -> f32 {
        values.sort_by(f32::total_cmp);
        values[values.len() / 2]
    }

    impl Measures {
        /// `closest[s]`: the first guide of strand `s` (a guide names itself).
        fn of(unstyled: &Groom, styled: &Groom, flags: &[bool], closest: &[u32]) -> Measures {
            let strands = styled.strand_count();
            let curl = |s: usize| {
                let p = styled.strand_points(s);
                curl_radius(&p[p.len() * 2 / 5..])
            };
            let radii =
                |guide: bool| median((0..strands).filter(|&s| flags[s] == guide).filter_map(curl).collect());
            let children: Vec<usize> = (0..strands).filter(|&s| !flags[s]).collect();
            let root = |s: usize| unstyled.strand_points(s)[0];
            let mid = |g: &Groom, s: usize| g.strand_points(s)[g.strand_range(s).len() / 2];
            let nearest = |c: usize, same: bool| {
                children
                    .iter()
                    .copied()
                    .filter(|&o| o != c && (!same || closest[o] == closest[c]))
                    .min_by(|&a, &b| root(a).distance(root(c)).total_cmp(&root(b).distance(root(c))))
            };
            // Which way a strand's curl turns: the sign of its summed torsion (triple products).
            let hand = |s: usize| {
                let p = styled.strand_points(s);
                let torsion: f32 = p[p.len() * 2 / 5..]
                    .windows(4)
                    .map(|w| (w[1] - w[0]).cross(w[2] - w[1]).dot(w[3] - w[2]))
                    .sum();
                torsion > 0.0
            };
            let (mut pairs, mut opposite) = (0, 0);
            let (mut before, mut after) = (0.0, 0.0);
            let (mut across, mut within) = ((0.0, 0), (0.0, 0));
            for &c in &children {
                if let Some(n) = nearest(c, true) {
                    before += mid(unstyled, c).distance(mid(unstyled, n));
                    after += mid(styled, c).distance(mid(styled, n));
                }
                if let Some(n) = nearest(c, false) {
                    pairs += 1;
                    opposite += usize::from(hand(c) != hand(n));
                    let sum = if closest[n] == closest[c] { &mut within } else { &mut across };
                    sum.0 += mid(styled, c).distance(mid(styled, n));
                    sum.1 += 1;
                }
            }
            let head = Head::default();
            Measures {
                guides_curl: radii(true),
                children_curl: radii(false),
                no_collapse: after / before,
                seam: (across.0 / across.1 as f32) / (within.0 / within.1 as f32),
                opposite: opposite as f32 / pairs as f32,
                stretch: children
                    .iter()
                    .map(|&s| (styled.strand_length(s) / unstyled.strand_length(s) - 1.0).abs())
                    .fold(0.0, f32::max),
                inside: children
                    .iter()
                    .flat_map(|&s| styled.strand_points(s)[1..].iter().filter(|p| head.implicit(**p) < 1.0))
                    .count(),
            }
        }
    }
}
