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
/// - as weighed: the median over the children of their guides' weighted curl radius, over the
///   guides' median: what the curl above would read if every child curled exactly as its guides
///   (children are not spread evenly over 30 guides: −9 to +15 % on curly heads over seeds 1–10);
/// - per child: the median over the children of each one's curl radius over its own guides'
///   (weighted by curvature, the inverse radius: a blend bends as much as its guides), which
///   the guides' sampling does not move;
/// - hang: the median over the children of how much higher (degrees) a child's weight hangs from
///   its root than its guides' (weighted): the elevation over the generated head's horizontal
///   (+y is up) of the mean of its points less its root;
/// - no-collapse: the mean distance at mid-length between each child and its nearest (by root)
///   child of the same first guide, styled over unstyled (issue 16 asks ≥ 0.5);
/// - seam: the mean distance at mid-length between each child and its nearest (by root) child,
///   over pairs bound to different first guides, divided by the same over pairs bound to the
///   same one (1 = no seam where the guides change);
/// - opposite: the share of those nearest pairs whose curls turn opposite ways (the sign of the
///   summed torsion, from 40 % of the length to the tip);
/// - the largest change of a child's length, and child vertices inside the head.
///
/// The control uses the guided run's guide flags and bindings. `COIF_BENCH_CONTROL=0` skips it;
/// `COIF_BENCH_SEEDS=1,2,3` generates the heads with those seeds (default 21).
mod children {
    use std::path::Path;

    use coif::analysis::curl_radius;
    use coif::generate::{generate, GenerateParams, Style};
    use coif::groom::Groom;
    use coif::guides::{CLOSEST_GUIDES, GUIDE_WEIGHTS};
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
        let seeds = std::env::var("COIF_BENCH_SEEDS").unwrap_or("21".into());
        let seeds: Vec<u64> =
            seeds.split(',').map(|s| s.parse().expect("COIF_BENCH_SEEDS: numbers")).collect();
        for preset in presets.split(',') {
            let path = format!("grooms/recipes/{preset}.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            let guided =
                recipe::parse(&format!("{text}\n[guides]\ncount = {GUIDES}\n"), Path::new(&path)).unwrap();
            let full = recipe::parse(&text, Path::new(&path)).unwrap();
            let runs =
                heads.iter().flat_map(|&(name, kind)| seeds.iter().map(move |&seed| (name, kind, seed)));
            for (name, style_kind, seed) in runs {
                let unstyled = generate(&GenerateParams {
                    strands: STRANDS,
                    vertices_per_strand: 32,
                    length: 0.30,
                    seed,
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
                let bindings = Bindings::of(&styled);
                let line = |what: &str, groom: &Groom| {
                    let m = Measures::of(&unstyled, groom, &flags, &closest, &bindings);
                    println!(
                        "{preset:<15} {name:<9} seed {seed:<3} {what:<8} curl {:+6.1} % (guides {:.2} cm)   \
                         as weighed {:+6.1} %   per child {:+6.1} %   hang {:+5.1}°   no-collapse {:.2}   \
                         seam {:.2}   opposite {:2.0} %   length change {:.2} %   inside head {}",
                        100.0 * (m.children_curl / m.guides_curl - 1.0),
                        100.0 * m.guides_curl,
                        100.0 * (m.as_weighed / m.guides_curl - 1.0),
                        100.0 * (m.per_child - 1.0),
                        m.hang,
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

    /// Each strand's guides as strand indices and their weights (a guide names itself).
    struct Bindings(Vec<[(usize, f32); 3]>);

    impl Bindings {
        fn of(styled: &Groom) -> Bindings {
            let by_id: std::collections::HashMap<u32, usize> =
                styled.strand_ids.iter().enumerate().map(|(s, &id)| (id, s)).collect();
            let closest = styled.attribute(CLOSEST_GUIDES).unwrap().floats();
            let weights = styled.attribute(GUIDE_WEIGHTS).unwrap().floats();
            Bindings(
                (0..styled.strand_count())
                    .map(|s| {
                        std::array::from_fn(|k| (by_id[&(closest[3 * s + k] as u32)], weights[3 * s + k]))
                    })
                    .collect(),
            )
        }

        /// Strand `s`'s guides' weighted mean of `value`, over the guides that have one.
        fn mean(&self, s: usize, value: impl Fn(usize) -> Option<f32>) -> Option<f32> {
            let (mut sum, mut total) = (0.0, 0.0);
            for &(g, w) in self.0[s].iter().filter(|(_, w)| *w > 0.0) {
                if let Some(v) = value(g) {
                    sum += w * v;
                    total += w;
                }
            }
            (total > 0.0).then(|| sum / total)
        }
    }

    struct Measures {
        guides_curl: f32,
        children_curl: f32,
        as_weighed: f32,
        per_child: f32,
        hang: f32,
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
        fn of(
            unstyled: &Groom,
            styled: &Groom,
            flags: &[bool],
            closest: &[u32],
            bindings: &Bindings,
        ) -> Measures {
            let strands = styled.strand_count();
            let curl = |s: usize| {
                let p = styled.strand_points(s);
                curl_radius(&p[p.len() * 2 / 5..])
            };
            let radii =
                |guide: bool| median((0..strands).filter(|&s| flags[s] == guide).filter_map(curl).collect());
            let children: Vec<usize> = (0..strands).filter(|&s| !flags[s]).collect();
            let guide_curl = |g: usize| curl(g).filter(|_| flags[g]);
            let per_child = children
                .iter()
                .filter_map(|&c| Some(curl(c)? * bindings.mean(c, |g| Some(1.0 / guide_curl(g)?))?))
                .collect();
            let as_weighed = children.iter().filter_map(|&c| bindings.mean(c, guide_curl)).collect();
            // How far above the horizontal (degrees) a strand's weight hangs from its root.
            let elevation = |s: usize| {
                let p = styled.strand_points(s);
                let hang = p.iter().map(|&q| q - p[0]).sum::<glam::Vec3>();
                Some(hang.try_normalize()?.y.clamp(-1.0, 1.0).asin().to_degrees())
            };
            let hang =
                children.iter().filter_map(|&c| Some(elevation(c)? - bindings.mean(c, elevation)?)).collect();
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
                as_weighed: median(as_weighed),
                per_child: median(per_child),
                hang: median(hang),
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
