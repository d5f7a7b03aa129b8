# Writes the crate files beside it with pxr (run from the repository root with pxr's python):
# layers coif must refuse as pxr reads them: curveVertexCounts declared int64[], uint[] or a
# scalar int (pxr finds no curves), and metersPerUnit 1e-30 (outside coif's units).
# Uses only pxr: `python tests/data/pxr_written_bad/make.py`.
from pxr import Sdf
def layer(meta, decl):
    return f'''#usda 1.0
(
    metersPerUnit = {meta}
)
def BasisCurves "c"
{{
    uniform token type = "linear"
    {decl}
    point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0)]
}}
'''
cases = {
  'counts_int64.usdc': layer(1, 'int64[] curveVertexCounts = [2, 2]'),
  'counts_uint.usdc': layer(1, 'uint[] curveVertexCounts = [2, 2]'),
  'counts_scalar.usdc': layer(1, 'int curveVertexCounts = 4'),
  'meters_per_unit_1e-30.usdc': layer('1e-30', 'int[] curveVertexCounts = [2, 2]'),
}
for name, text in cases.items():
    l = Sdf.Layer.CreateAnonymous('x.usda'); l.ImportFromString(text)
    l.Export('tests/data/pxr_written_bad/' + name)
# Declared int[] but holding another type's values (a crate keeps each value's own type; pxr's
# typed reads find no curves in them).
from pxr import Vt
for name, held in [('int64', Vt.Int64Array([2, 2])), ('uint', Vt.UIntArray([2, 2]))]:
    l = Sdf.Layer.CreateAnonymous('x.usda'); l.ImportFromString(layer(1, 'int[] curveVertexCounts = [2, 2]'))
    l.GetAttributeAtPath('/c.curveVertexCounts').SetInfo('default', held)
    l.Export(f'tests/data/pxr_written_bad/counts_int_holding_{name}.usdc')
# Floats held as another float type: pxr's typed reads find no widths in `float[] widths` holding
# double[] or half[] (its extent leaves them out), and no points in `point3f[] points` holding
# double3[] (no extent at all).
from pxr import Gf
corners = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0)]
for name, path, held in [
    ('widths_float_holding_double', '/c.widths', Vt.DoubleArray([0.01] * 4)),
    ('widths_float_holding_half', '/c.widths', Vt.HalfArray([0.01] * 4)),
    ('points_point3f_holding_double3', '/c.points', Vt.Vec3dArray([Gf.Vec3d(*p) for p in corners])),
]:
    l = Sdf.Layer.CreateAnonymous('x.usda')
    l.ImportFromString(layer(1, 'int[] curveVertexCounts = [2, 2]\n    float[] widths = [0.01, 0.01, 0.01, 0.01] (interpolation = "vertex")'))
    l.GetAttributeAtPath(path).SetInfo('default', held)
    l.Export(f'tests/data/pxr_written_bad/{name}.usdc')
