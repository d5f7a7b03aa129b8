//! How many values a curve primvar holds at each rate, and how `varying` values (one per segment
//! end) map onto control points. The groom keeps widths and attributes per vertex or per strand;
//! readers spread a file's `varying` values onto the vertices with [`varying_to_vertex`] and
//! writers recover them with [`vertex_to_varying`], so an unstyled round trip gives back the
//! file's values exactly. [`widths_at`] decides at which rate a group's widths are written.
//!
//! The segment ends of a cubic curve (USD's `UsdGeomBasisCurves` segment indexing, RenderMan's
//! and Alembic's `varying`): Bézier (vstep 3) segments end on every third control point; a
//! nonperiodic B-spline or Catmull-Rom curve of `n` points has `n − 3` segments whose ends lie at
//! (Catmull-Rom) or next to (B-spline) control points `1 ..= n − 2`; pinned ones (USD only) have
//! `n − 1` segments, one end per control point. Linear curves have one end per point.
use crate::groom::CurveBasis;
use crate::groups::{CurveWrap, Interpolation};

/// Whether `vertices` control points make at least one whole segment of the basis, as USD's
/// `BasisCurves` requires: cubic curves need 4 (Bézier 3k + 1; pinned non-Bézier ones 2).
/// Linear strands of one point are refused elsewhere, for every format.
pub fn is_whole_curve(basis: CurveBasis, wrap: CurveWrap, vertices: usize) -> bool {
    match (basis, wrap) {
        (CurveBasis::Linear, _) => true,
        (CurveBasis::Bezier, _) => vertices >= 4 && (vertices - 1) % 3 == 0,
        (_, CurveWrap::Pinned) => vertices >= 2,
        _ => vertices >= 4,
    }
}

/// What [`is_whole_curve`] asks of a curve of `basis`, in words.
pub fn whole_curve_rule(basis: CurveBasis) -> &'static str {
    if basis == CurveBasis::Bezier {
        "3k + 1 (at least 4)"
    } else {
        "at least 4"
    }
}

/// Values per curve of `vertices` control points for `varying` interpolation (segments + 1).
pub fn varying_count(basis: CurveBasis, wrap: CurveWrap, vertices: usize) -> usize {
    match (basis, wrap) {
        (CurveBasis::Linear, _) => vertices,
        (CurveBasis::Bezier, _) => vertices.saturating_sub(1) / 3 + 1,
        (_, CurveWrap::Pinned) => vertices,
        (_, _) => vertices.saturating_sub(2).max(1),
    }
}

/// Which control point varying value `j` of a curve sits on (or nearest to).
fn vertex_of_end(basis: CurveBasis, ends: usize, vertices: usize, j: usize) -> usize {
    if ends == vertices {
        j
    } else if basis == CurveBasis::Bezier {
        3 * j
    } else {
        (j + 1).min(vertices - 1)
    }
}

/// Per-vertex values from `varying` ones (`components` numbers per value, each curve's
/// [`varying_count`] values in turn; the caller checked the total). A control point on a segment
/// end takes that end's value; Bézier handles between two ends are interpolated linearly; the
/// first and last points of a nonperiodic B-spline or Catmull-Rom curve, which no segment
/// reaches, repeat their neighbour's.
pub fn varying_to_vertex<T: Spread>(
    basis: CurveBasis,
    wrap: CurveWrap,
    counts: impl IntoIterator<Item = usize>,
    values: &[T],
    components: usize,
) -> Vec<T> {
    let mut out = Vec::with_capacity(values.len());
    let mut start = 0;
    for n in counts {
        let m = varying_count(basis, wrap, n);
        let curve = &values[start * components..(start + m) * components];
        let value = |j: usize| &curve[j * components..(j + 1) * components];
        for i in 0..n {
            if m == n {
                out.extend_from_slice(value(i));
            } else if basis == CurveBasis::Bezier {
                let (j, t) = (i / 3, (i % 3) as f32 / 3.0);
                if t == 0.0 || j + 1 >= m {
                    out.extend_from_slice(value(j.min(m - 1)));
                } else {
                    out.extend(value(j).iter().zip(value(j + 1)).map(|(&a, &b)| T::between(a, b, t)));
                }
            } else {
                out.extend_from_slice(value(i.saturating_sub(1).min(m - 1)));
            }
        }
        start += m;
    }
    out
}

/// A number a Bézier handle's value is made of from the segment ends' `varying` values.
pub trait Spread: Copy {
    /// The value a fraction `t` of the way from `a` to `b`.
    fn between(a: Self, b: Self, t: f32) -> Self;
}

impl Spread for f32 {
    fn between(a: f32, b: f32, t: f32) -> f32 {
        a + (b - a) * t
    }
}

/// Integers (ids) are not blended: a handle takes the nearer end's.
impl Spread for i64 {
    fn between(a: i64, b: i64, t: f32) -> i64 {
        if t < 0.5 {
            a
        } else {
            b
        }
    }
}

/// The `varying` values per-vertex `values` were spread from by [`varying_to_vertex`], or `None`
/// when spreading them again would not give `values` back bit for bit (the vertices were edited,
/// resampled or came per vertex).
pub fn vertex_to_varying(
    basis: CurveBasis,
    wrap: CurveWrap,
    counts: &[usize],
    values: &[f32],
    components: usize,
) -> Option<Vec<f32>> {
    let mut out = Vec::new();
    let mut start = 0;
    for &n in counts {
        let m = varying_count(basis, wrap, n);
        for j in 0..m {
            let at = (start + vertex_of_end(basis, m, n, j)) * components;
            out.extend_from_slice(values.get(at..at + components)?);
        }
        start += n;
    }
    let again = varying_to_vertex(basis, wrap, counts.iter().copied(), &out, components);
    (again.len() == values.len() && again.iter().zip(values).all(|(a, b)| a.to_bits() == b.to_bits()))
        .then_some(out)
}

/// A group's widths as a file gave them: `interpolation` (`None`: per vertex) and its values. The
/// file's rate is kept while the values still fit it — one value for the group (`Constant`), one
/// per strand (`Uniform`), spread segment-end values (`Varying`) — else they are per vertex.
/// `counts` are the group's vertex counts, `widths` its per-vertex widths; `wrap` is the one whose
/// varying count the output format uses.
pub fn widths_at(
    interpolation: Option<Interpolation>,
    basis: CurveBasis,
    wrap: CurveWrap,
    counts: &[usize],
    widths: &[f32],
) -> Option<(Interpolation, Vec<f32>)> {
    let same = |w: &[f32]| w.iter().all(|v| v.to_bits() == w[0].to_bits());
    match interpolation? {
        Interpolation::Constant => {
            (!widths.is_empty() && same(widths)).then(|| (Interpolation::Constant, vec![widths[0]]))
        }
        Interpolation::Uniform => {
            let mut out = Vec::with_capacity(counts.len());
            let mut start = 0;
            for &n in counts {
                let strand = widths.get(start..start + n).filter(|w| !w.is_empty() && same(w))?;
                out.push(strand[0]);
                start += n;
            }
            Some((Interpolation::Uniform, out))
        }
        Interpolation::Varying => {
            vertex_to_varying(basis, wrap, counts, widths, 1).map(|v| (Interpolation::Varying, v))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varying_counts_follow_the_segment_counts() {
        // USD's segment indexing: nonperiodic (n - 4) / vstep + 1 segments, pinned n - 1.
        assert_eq!(varying_count(CurveBasis::CatmullRom, CurveWrap::Nonperiodic, 6), 4);
        assert_eq!(varying_count(CurveBasis::BSpline, CurveWrap::Nonperiodic, 4), 2);
        assert_eq!(varying_count(CurveBasis::CatmullRom, CurveWrap::Pinned, 6), 6);
        assert_eq!(varying_count(CurveBasis::Bezier, CurveWrap::Nonperiodic, 7), 3);
        assert_eq!(varying_count(CurveBasis::Linear, CurveWrap::Nonperiodic, 5), 5);
    }

    #[test]
    fn varying_values_come_back_from_the_vertices_they_were_spread_onto() {
        let cases = [
            (CurveBasis::CatmullRom, CurveWrap::Nonperiodic, vec![6, 4], vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            (CurveBasis::BSpline, CurveWrap::Nonperiodic, vec![5], vec![0.5, 0.25, 0.125]),
            (CurveBasis::Bezier, CurveWrap::Nonperiodic, vec![7, 4], vec![3.0, 6.0, 0.0, 1.0, 2.0]),
            (CurveBasis::CatmullRom, CurveWrap::Pinned, vec![3], vec![1.0, 2.0, 3.0]),
        ];
        for (basis, wrap, counts, varying) in cases {
            let vertices = varying_to_vertex(basis, wrap, counts.iter().copied(), &varying, 1);
            assert_eq!(vertices.len(), counts.iter().sum::<usize>(), "{basis:?}");
            assert_eq!(vertex_to_varying(basis, wrap, &counts, &vertices, 1), Some(varying), "{basis:?}");
        }
        // Catmull-Rom segment ends sit on points 1..=n-2; the unreached ends repeat them.
        let spread =
            varying_to_vertex(CurveBasis::CatmullRom, CurveWrap::Nonperiodic, [5], &[1.0, 2.0, 3.0], 1);
        assert_eq!(spread, [1.0, 1.0, 2.0, 3.0, 3.0]);
        // Bézier handles lie a third and two thirds of the way between two ends.
        let spread = varying_to_vertex(CurveBasis::Bezier, CurveWrap::Nonperiodic, [4], &[0.0, 3.0], 1);
        assert_eq!(spread, [0.0, 1.0, 2.0, 3.0]);
        // Values per vertex that no varying values give are not varying.
        let edited = [1.0, 1.5, 2.0, 3.0, 3.0];
        assert_eq!(vertex_to_varying(CurveBasis::CatmullRom, CurveWrap::Nonperiodic, &[5], &edited, 1), None);
    }

    #[test]
    fn widths_keep_their_rate_while_the_values_fit_it() {
        let (basis, wrap) = (CurveBasis::Linear, CurveWrap::Nonperiodic);
        let counts = [2, 3];
        let constant = [0.5; 5];
        let uniform = [0.5, 0.5, 0.25, 0.25, 0.25];
        assert_eq!(
            widths_at(Some(Interpolation::Constant), basis, wrap, &counts, &constant),
            Some((Interpolation::Constant, vec![0.5]))
        );
        assert_eq!(widths_at(Some(Interpolation::Constant), basis, wrap, &counts, &uniform), None);
        assert_eq!(
            widths_at(Some(Interpolation::Uniform), basis, wrap, &counts, &uniform),
            Some((Interpolation::Uniform, vec![0.5, 0.25]))
        );
        let tapered = [0.5, 0.4, 0.25, 0.25, 0.25];
        assert_eq!(widths_at(Some(Interpolation::Uniform), basis, wrap, &counts, &tapered), None);
        assert_eq!(widths_at(None, basis, wrap, &counts, &constant), None);
    }
}
