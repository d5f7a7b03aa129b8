//! Triangle meshes from Wavefront OBJ files (through the `tobj` crate), for mesh obstacles: a
//! scanned or modelled head the hair collides with. Polygons are triangulated; every object in
//! the file joins one mesh; materials, normals and texture coordinates are ignored. Units are
//! taken as metres with Y up, like the rest of coif.
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

/// The vertices and triangles of every object in an OBJ file.
pub fn read_triangles(path: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    crate::io::input::check_regular(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_triangles(&bytes, path)
}

/// [`read_triangles`] on bytes already in memory; `path` names them in errors.
pub fn parse_triangles(bytes: &[u8], path: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    check_face_indices(bytes, path)?;
    // Material libraries are not read: a mesh obstacle needs only its surface.
    let mut reader = LineCounter::new(bytes);
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| {
            let line = reader.last_line(bytes);
            Error::format(path, format!("{line}: not a readable Wavefront OBJ file: {e}"))
        })?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let base = vertices.len() as u32;
        for (k, p) in mesh.positions.chunks_exact(3).enumerate() {
            let v = Vec3::new(p[0], p[1], p[2]);
            let key = format!("vertex {}", k + 1);
            if let Err(message) = crate::validate::vector(&key, v.into(), crate::validate::COORDINATE) {
                return Err(Error::format(path, format!("object '{}': {message}", model.name)));
            }
            vertices.push(v);
        }
        let count = (mesh.positions.len() / 3) as u32;
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i >= count) {
                return Err(Error::format(
                    path,
                    format!(
                        "object '{}': triangle {} names vertex {} of {count}",
                        model.name,
                        t + 1,
                        bad + 1
                    ),
                ));
            }
            triangles.push([base + tri[0], base + tri[1], base + tri[2]]);
        }
    }
    if triangles.is_empty() {
        return Err(Error::format(path, "the OBJ file has no triangles (no `f` faces)"));
    }
    if !triangles.iter().any(|t| has_area(t.map(|i| vertices[i as usize]))) {
        return Err(Error::format(
            path,
            format!(
                "the mesh has no area: the corners of each of its {} triangles coincide or lie on one line",
                triangles.len()
            ),
        ));
    }
    Ok((vertices, triangles))
}

/// Whether a triangle spans a surface: its corners neither coincide nor lie on one line (to
/// f32's precision at its size). A mesh of none has no inside, outside or normal to collide with.
fn has_area(corners: [Vec3; 3]) -> bool {
    let [a, b, c] = corners;
    let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    // Twice the area over the longest edge squared is the sine of an angle: below 1e-6, rounding.
    (b - a).cross(c - a).length() > 1e-6 * longest
}

/// The OBJ bytes as `tobj` reads them, counting the lines it has begun: `tobj` refuses a line
/// just after reading it (its indices are checked before, by [`check_face_indices`]), so the
/// count names that line.
struct LineCounter<'a> {
    rest: &'a [u8],
    lines_begun: usize,
    at_line_start: bool,
}

impl<'a> LineCounter<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        LineCounter { rest: bytes, lines_begun: 0, at_line_start: true }
    }

    /// The line last read and its text, for an error message.
    fn last_line(&self, bytes: &[u8]) -> String {
        let number = self.lines_begun;
        match lines_and_text(bytes).nth(number.saturating_sub(1)).flatten() {
            Some(text) => {
                let shown: String = text.chars().take(60).collect();
                let more = if shown.len() < text.len() { "…" } else { "" };
                format!("line {number} ('{shown}{more}')")
            }
            None => format!("line {number} (not UTF-8)"),
        }
    }
}

impl std::io::Read for LineCounter<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.rest.len());
        buf[..n].copy_from_slice(&self.rest[..n]);
        std::io::BufRead::consume(self, n);
        Ok(n)
    }
}

impl std::io::BufRead for LineCounter<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(self.rest)
    }

    fn consume(&mut self, amount: usize) {
        for &byte in &self.rest[..amount] {
            self.lines_begun += usize::from(self.at_line_start);
            self.at_line_start = byte == b'\n';
        }
        self.rest = &self.rest[amount..];
    }
}

/// The lines of an OBJ file and their words, cut exactly as `tobj` cuts them (`BufRead::lines`,
/// then Unicode white space: vertical tab and no-break space separate words too), so the check
/// below sees the indices tobj will use. A line that is not UTF-8 makes tobj refuse the file, so
/// it has no words here.
fn lines_and_words(bytes: &[u8]) -> impl Iterator<Item = (usize, Vec<&str>)> {
    lines_and_text(bytes).enumerate().map(|(number, line)| {
        let words = line.map_or_else(Vec::new, |l| l.split_whitespace().collect());
        (number, words)
    })
}

/// The lines of an OBJ file as `tobj` reads them; `None` for a line that is not UTF-8.
fn lines_and_text(bytes: &[u8]) -> impl Iterator<Item = Option<&str>> {
    bytes
        .split(|&b| b == b'\n')
        .map(|line| std::str::from_utf8(line.strip_suffix(b"\r").unwrap_or(line)).ok())
}

/// The kinds of element a face corner names, in the order of its `v/vt/vn` parts.
const CORNER_PARTS: [&str; 3] = ["vertex", "texture coordinate", "normal"];

/// Refuses a face or line that names an element the file does not have, before `tobj` sees it:
/// `tobj` multiplies indices by 3 unchecked, so a huge or out-of-range relative index panics on
/// overflow (or, without overflow checks, wraps past its own bounds check). Indices count from 1;
/// negative ones count back from the elements defined so far, as in `tobj`.
fn check_face_indices(bytes: &[u8], path: &Path) -> Result<()> {
    let kind = |word: &str| match word {
        "v" => Some(0),
        "vt" => Some(1),
        "vn" => Some(2),
        _ => None,
    };
    let mut totals = [0i64; 3];
    for (_, words) in lines_and_words(bytes) {
        if let Some(k) = words.first().and_then(|w| kind(w)) {
            totals[k] += 1;
        }
    }
    let mut defined = [0i64; 3];
    for (number, words) in lines_and_words(bytes) {
        match words.first().copied() {
            Some("f" | "l") => {}
            Some(word) => {
                if let Some(k) = kind(word) {
                    defined[k] += 1;
                }
                continue;
            }
            None => continue,
        }
        // tobj keeps a face of no corners, then fails on it at the end of the object.
        if words.len() == 1 {
            return Err(Error::format(path, format!("line {}: '{}' with no corners", number + 1, words[0])));
        }
        for corner in &words[1..] {
            for (part, text) in corner.split('/').enumerate().take(CORNER_PARTS.len()) {
                // Unparsable parts are left to tobj, which refuses them.
                let Ok(index) = text.parse::<i64>() else {
                    continue;
                };
                let known = index.checked_neg().is_some_and(|back| {
                    (1..=totals[part]).contains(&index) || (1..=defined[part]).contains(&back)
                });
                if !known {
                    return Err(Error::format(
                        path,
                        format!(
                            "line {}: a face names {} {index}, but the file has {} (indices count from 1, \
                             or back from -1)",
                            number + 1,
                            CORNER_PARTS[part],
                            totals[part]
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.obj");
        std::fs::write(&path, text).unwrap();
        (dir, path)
    }

    #[test]
    fn quads_are_triangulated_and_objects_join_one_mesh() {
        let (_dir, path) = write(
            "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
             o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n",
        );
        let (vertices, triangles) = read_triangles(&path).unwrap();
        assert_eq!(vertices.len(), 7);
        assert_eq!(triangles.len(), 3);
        for t in &triangles {
            assert!(t.iter().all(|&i| (i as usize) < vertices.len()));
        }
        // The second object's triangle uses its own vertices.
        assert!(triangles.contains(&[4, 5, 6]));
    }

    #[test]
    fn meshes_without_area_are_refused() {
        // Collinear corners, coincident ones, and a triangle a millionth as tall as it is long.
        for text in [
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n",
            "v 0.1 0.2 0.3\nv 0.1 0.2 0.3\nv 0.1 0.2 0.3\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0.5 1e-7 0\nv 5 5 5\nf 1 2 3\nf 4 4 4\n",
        ] {
            let (_dir, path) = write(text);
            let e = read_triangles(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            assert!(e.to_string().contains("mesh.obj: the mesh has no area"), "{e}");
        }
        // A mesh with some degenerate triangles among real ones is read whole.
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n");
        assert_eq!(read_triangles(&path).unwrap().1.len(), 2);
        // A thin sliver (1 mm tall over 1 m) has area.
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\nv 0.5 0.001 0\nf 1 2 3\n");
        assert_eq!(read_triangles(&path).unwrap().1.len(), 1);
    }

    #[test]
    fn bad_files_name_the_file_and_the_reason() {
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\n");
        let e = read_triangles(&path).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("mesh.obj") && e.to_string().contains("no triangles"), "{e}");

        let (_dir, path) = write("v 0 0 zero\nf 1 1 1\n");
        let e = read_triangles(&path).unwrap_err();
        assert!(e.to_string().contains("mesh.obj") && e.to_string().contains("OBJ"), "{e}");

        // Indices beyond the file's elements, relative ones reaching before the first, and 0:
        // tobj would overflow multiplying the first two (found by the obj_reader fuzz target).
        for (face, names) in [
            (
                "f 1//6148914691236517206 2//1 3//1",
                "line 5: a face names normal 6148914691236517206, but the file has 1",
            ),
            ("f 1 2 4", "line 5: a face names vertex 4, but the file has 3"),
            ("f -1 -2 -4", "line 5: a face names vertex -4"),
            ("f 1/0 2/1 3/1", "texture coordinate 0"),
        ] {
            let (_dir, path) = write(&format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n{face}\nvt 0 0\n"));
            let e = read_triangles(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            assert!(e.to_string().contains("mesh.obj") && e.to_string().contains(names), "{e}");
        }
        // Words split as tobj splits them: a vertical tab ends "-8" here (found by the fuzz
        // target after 5 M runs: tobj saw texture coordinate -8 of 1 and overflowed).
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-8\u{b} 2/1 3/1\r\n");
        let e = read_triangles(&path).unwrap_err();
        assert!(e.to_string().contains("line 5: a face names texture coordinate -8"), "{e}");
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3//1 -2//-1 -1//1\n");
        assert_eq!(read_triangles(&path).unwrap().1, vec![[0, 1, 2]]);

        // Lines tobj refuses are named with their text, counted as tobj counts them (a last line
        // without a line break, CRLF breaks, a line that is not UTF-8).
        for (text, names) in [
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 x 0\nf 1 2 3\n", "line 4 ('v 1 x 0'): not a readable"),
            ("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\nvn 0 1\r\n", "line 5 ('vn 0 1'): "),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nvt a b", "line 5 ('vt a b'): "),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 x\n", "line 5 ('f 1 2 x'): "),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0 0\nf 1 2 3\n", "line 3 ('v 0 1 0 0'): "),
            ("v 0 0 0\nv 1 0 0\n\n\nv 0 1 0\nf 1 2 3\n# \u{ff}\nv \u{1} 0 0\n", "line 8 ('v \u{1} 0 0'): "),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf\n", "line 5: 'f' with no corners"),
        ] {
            let (_dir, path) = write(text);
            let e = read_triangles(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            assert!(e.to_string().contains("mesh.obj") && e.to_string().contains(names), "{text:?}: {e}");
        }
        let (_dir, path) = write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        std::fs::write(&path, b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\xff\xfe\n").unwrap();
        let e = read_triangles(&path).unwrap_err();
        assert!(e.to_string().contains("line 5 (not UTF-8): "), "{e}");

        let missing = Path::new("/nonexistent/head.obj");
        let e = read_triangles(missing).unwrap_err();
        assert!(e.to_string().contains("head.obj") && e.exit_code() == 2, "{e}");
    }
}
