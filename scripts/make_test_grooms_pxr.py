"""Writes tests/data/houdini_groom.usda: a groom laid out the way Houdini's USD export does,
authored with usd-core (pxr) so the file is what a real USD writer produces.

  .deps/venv/bin/python scripts/make_test_grooms_pxr.py tests/data/houdini_groom.usda

Centimetres, Y up, /groom (Xform, translated) holding three BasisCurves prims with different
bases and point counts per strand:
  guides  cubic Catmull-Rom, wrap pinned, purpose "guide", primvars:rest (point3f, vertex)
  hair    linear children, varying widths, primvars:guide_curve_index (int, uniform),
          primvars:st (texCoord2f, uniform), primvars:N (normal3f, uniform)
  fuzz    cubic B-spline, nonperiodic, constant width
and /skin, a Mesh (a quad strip) with primvars:rest.
"""
import math
import sys

from pxr import Gf, Sdf, Usd, UsdGeom, Vt


def strand(root, length, count, bend):
    """`count` points from `root` upwards (+Y), bending towards +X."""
    points = []
    for i in range(count):
        t = i / (count - 1)
        points.append(Gf.Vec3f(root[0] + bend * t * t, root[1] + length * t, root[2] + 0.3 * math.sin(3 * t)))
    return points


def main(out):
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    groom = UsdGeom.Xform.Define(stage, "/groom")
    stage.SetDefaultPrim(groom.GetPrim())
    groom.AddTranslateOp().Set(Gf.Vec3d(0, 150, 0))

    guides = UsdGeom.BasisCurves.Define(stage, "/groom/guides")
    guides.CreateTypeAttr(UsdGeom.Tokens.cubic)
    guides.CreateBasisAttr(UsdGeom.Tokens.catmullRom)
    guides.CreateWrapAttr(UsdGeom.Tokens.pinned)
    guides.CreatePurposeAttr(UsdGeom.Tokens.guide)
    counts = [5, 6, 7]
    points = []
    for k, n in enumerate(counts):
        points += strand((2.0 * k, 0, 0), 10.0 + k, n, 1.5)
    guides.CreateCurveVertexCountsAttr(counts)
    guides.CreatePointsAttr(Vt.Vec3fArray(points))
    guides.CreateWidthsAttr([0.02 + 0.001 * i for i in range(len(points))])
    guides.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    rest = UsdGeom.PrimvarsAPI(guides).CreatePrimvar("rest", Sdf.ValueTypeNames.Point3fArray, UsdGeom.Tokens.vertex)
    rest.Set(Vt.Vec3fArray([p + Gf.Vec3f(0, 0, 0.5) for p in points]))

    hair = UsdGeom.BasisCurves.Define(stage, "/groom/hair")
    hair.CreateTypeAttr(UsdGeom.Tokens.linear)
    counts = [4, 5, 6, 7, 8, 4]
    points = []
    for k, n in enumerate(counts):
        points += strand((0.7 * k + 0.1, 0, 0.4), 9.0 + 0.5 * k, n, 1.0)
    hair.CreateCurveVertexCountsAttr(counts)
    hair.CreatePointsAttr(Vt.Vec3fArray(points))
    hair.CreateWidthsAttr([0.01 + 0.0005 * i for i in range(len(points))])
    hair.SetWidthsInterpolation(UsdGeom.Tokens.varying)
    api = UsdGeom.PrimvarsAPI(hair)
    api.CreatePrimvar("guide_curve_index", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.uniform).Set(
        [0, 0, 1, 1, 2, 2]
    )
    api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.uniform).Set(
        [(0.1 * k, 0.5) for k in range(len(counts))]
    )
    api.CreatePrimvar("N", Sdf.ValueTypeNames.Normal3fArray, UsdGeom.Tokens.uniform).Set(
        [Gf.Vec3f(0, 1, 0), Gf.Vec3f(0, 0, 1), Gf.Vec3f(1, 0, 0), Gf.Vec3f(0.6, 0.8, 0), Gf.Vec3f(0, 0.6, 0.8), Gf.Vec3f(0.8, 0, 0.6)]
    )

    fuzz = UsdGeom.BasisCurves.Define(stage, "/groom/fuzz")
    fuzz.CreateTypeAttr(UsdGeom.Tokens.cubic)
    fuzz.CreateBasisAttr(UsdGeom.Tokens.bspline)
    counts = [5, 6]
    points = []
    for k, n in enumerate(counts):
        points += strand((-1.0 - k, 0, -0.5), 4.0, n, -0.8)
    fuzz.CreateCurveVertexCountsAttr(counts)
    fuzz.CreatePointsAttr(Vt.Vec3fArray(points))
    fuzz.CreateWidthsAttr([0.015])
    fuzz.SetWidthsInterpolation(UsdGeom.Tokens.constant)

    skin = UsdGeom.Mesh.Define(stage, "/skin")
    skin_points = [Gf.Vec3f(x, 150.0, z) for z in (-1.0, 1.0) for x in (-3.0, 0.0, 3.0, 6.0)]
    skin.CreatePointsAttr(skin_points)
    skin.CreateFaceVertexCountsAttr([4, 4, 4])
    skin.CreateFaceVertexIndicesAttr([0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6])
    UsdGeom.PrimvarsAPI(skin).CreatePrimvar("rest", Sdf.ValueTypeNames.Point3fArray, UsdGeom.Tokens.vertex).Set(
        skin_points
    )
    stage.GetRootLayer().Export(out)


if __name__ == "__main__":
    main(sys.argv[1])
