"""Test helper: what usd-core (pxr) itself sees in a stage, as JSON, and stages authored by pxr.

  pxr_probe.py dump STAGE [--time T]     curves, primvars, metadata, extents, validation findings
  pxr_probe.py blended STAGE T0 T1 W     world points of each curve prim with every Xform's local
                                         matrix blended between T0 and T1 (W = weight of T1):
                                         scale and translation lerped, rotation slerped
  pxr_probe.py frames STAGE FIRST LAST   the timeline metadata, and the world points of each curve
                                         prim at every whole frame FIRST..LAST, in metres, Y up
  pxr_probe.py author-transformed OUT    nested Xforms, cm units, Z up, two curve prims, samples
  pxr_probe.py author-composed DIR       a stage that references a layer with a variant set
  pxr_probe.py export IN OUT             IN saved by pxr in OUT's format (e.g. .usda to .usdc)
  pxr_probe.py batch JOBS.json           several jobs in one run: ["export", IN, OUT] (a layer, arcs
                                         kept) or ["flatten", IN, OUT, [PRIM_PATH:]SET=NAME...] (the
                                         composed stage, variants selected in the session layer)
"""
import json
import sys

from pxr import Gf, Sdf, Usd, UsdGeom, UsdValidation, Vt


def floats(values):
    out = []
    for v in values:
        if isinstance(v, (int, float)):
            out.append(float(v))
        else:
            out.extend(float(x) for x in v)
    return out


def dump(path, time=None):
    stage = Usd.Stage.Open(path)
    code = Usd.TimeCode.Default() if time is None else Usd.TimeCode(time)
    result = {
        "defaultPrim": stage.GetRootLayer().defaultPrim,
        "upAxis": UsdGeom.GetStageUpAxis(stage),
        "metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage),
        "hasAuthoredMetersPerUnit": UsdGeom.StageHasAuthoredMetersPerUnit(stage),
        "startTimeCode": stage.GetStartTimeCode() if stage.HasAuthoredTimeCodeRange() else None,
        "endTimeCode": stage.GetEndTimeCode() if stage.HasAuthoredTimeCodeRange() else None,
        "timeCodesPerSecond": stage.GetTimeCodesPerSecond(),
        "curves": [],
        "meshes": [],
        "prims": [[str(p.GetPath()), str(p.GetTypeName())] for p in stage.Traverse()],
        "userProperties": {
            str(a.GetPath()): {"type": str(a.GetTypeName()), "value": a.Get(code)}
            for p in stage.Traverse()
            for a in p.GetAuthoredPropertiesInNamespace("userProperties")
            if isinstance(a, Usd.Attribute) and isinstance(a.Get(code), (int, float, str))
        },
    }
    cache = UsdGeom.XformCache(code)
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        curves = UsdGeom.BasisCurves(prim)
        points = curves.GetPointsAttr().Get(code)
        world = cache.GetLocalToWorldTransform(prim)
        entry = {
            "path": str(prim.GetPath()),
            "parent": str(prim.GetParent().GetTypeName()),
            "type": curves.GetTypeAttr().Get(),
            "basis": curves.GetBasisAttr().Get(),
            "wrap": curves.GetWrapAttr().Get(),
            "purpose": UsdGeom.Imageable(prim).GetPurposeAttr().Get(),
            # What renderers and DCC tools act on: inherited from imageable ancestors.
            "computedPurpose": UsdGeom.Imageable(prim).ComputePurpose(),
            "computedVisibility": UsdGeom.Imageable(prim).ComputeVisibility(code),
            "segmentEnds": curves.ComputeVaryingDataSize(code),
            "counts": list(curves.GetCurveVertexCountsAttr().Get(code)),
            "points": floats(points),
            "world_points": floats(world.Transform(Gf.Vec3d(p)) for p in points),
            "widths": floats(curves.GetWidthsAttr().Get(code) or []),
            "widthsInterpolation": curves.GetWidthsInterpolation(),
            "pointsTimeSamples": curves.GetPointsAttr().GetTimeSamples(),
            "extent": floats(curves.GetExtentAttr().Get(code) or []),
            "computedExtent": floats(UsdGeom.Boundable.ComputeExtentFromPlugins(curves, code) or []),
            "primvars": {},
            # The curves' own normals (an orientation), velocities and accelerations (motion).
            "normals": {
                "interpolation": curves.GetNormalsInterpolation(),
                "type": str(curves.GetNormalsAttr().GetTypeName()),
                "values": floats(curves.GetNormalsAttr().Get(code) or []),
            } if curves.GetNormalsAttr().HasAuthoredValue() else None,
            "velocities": floats(curves.GetVelocitiesAttr().Get(code) or [])
            if curves.GetVelocitiesAttr().HasAuthoredValue() else None,
            "accelerations": floats(curves.GetAccelerationsAttr().Get(code) or [])
            if curves.GetAccelerationsAttr().HasAuthoredValue() else None,
        }
        for primvar in UsdGeom.PrimvarsAPI(prim).GetAuthoredPrimvars():
            value = primvar.ComputeFlattened(code)
            entry["primvars"][primvar.GetPrimvarName()] = {
                "type": str(primvar.GetTypeName()),
                "interpolation": primvar.GetInterpolation(),
                "elementSize": primvar.GetElementSize(),
                "timeSamples": primvar.GetAttr().GetTimeSamples(),
                "values": floats(value) if value is not None else None,
            }
        result["curves"].append(entry)
    result["nurbs"] = []
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.NurbsCurves):
            continue
        nurbs = UsdGeom.NurbsCurves(prim)
        points = nurbs.GetPointsAttr().Get(code)
        world = cache.GetLocalToWorldTransform(prim)
        result["nurbs"].append({
            "path": str(prim.GetPath()),
            "order": list(nurbs.GetOrderAttr().Get(code) or []),
            "knots": floats(nurbs.GetKnotsAttr().Get(code) or []),
            "counts": list(nurbs.GetCurveVertexCountsAttr().Get(code)),
            "world_points": floats(world.Transform(Gf.Vec3d(p)) for p in points),
            "widths": floats(nurbs.GetWidthsAttr().Get(code) or []),
        })
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get(code)
        world = cache.GetLocalToWorldTransform(prim)
        result["meshes"].append({
            "path": str(prim.GetPath()),
            "counts": list(mesh.GetFaceVertexCountsAttr().Get(code) or []),
            "indices": list(mesh.GetFaceVertexIndicesAttr().Get(code) or []),
            "holeIndices": list(mesh.GetHoleIndicesAttr().Get(code) or []),
            "points": floats(points or []),
            "world_points": floats(world.Transform(Gf.Vec3d(p)) for p in points or []),
            "orientation": mesh.GetOrientationAttr().Get(),
            "subdivisionScheme": mesh.GetSubdivisionSchemeAttr().Get(),
            "computedVisibility": mesh.ComputeVisibility(code),
            "pointsTimeSamples": mesh.GetPointsAttr().GetTimeSamples(),
            "extent": floats(mesh.GetExtentAttr().Get(code) or []),
            "computedExtent": floats(UsdGeom.Boundable.ComputeExtentFromPlugins(mesh, code) or []),
            "normals": {
                "interpolation": mesh.GetNormalsInterpolation(),
                "type": str(mesh.GetNormalsAttr().GetTypeName()),
                "values": floats(mesh.GetNormalsAttr().Get(code) or []),
            } if mesh.GetNormalsAttr().HasAuthoredValue() else None,
            # Authored primvars, flattened through their indices.
            "primvars": {
                pv.GetPrimvarName(): {
                    "type": str(pv.GetTypeName()),
                    "role": str(pv.GetTypeName().role),
                    "interpolation": pv.GetInterpolation(),
                    "indexed": pv.IsIndexed(),
                    "values": floats(pv.ComputeFlattened(code)),
                }
                for pv in UsdGeom.PrimvarsAPI(prim).GetPrimvarsWithAuthoredValues()
            },
        })
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    findings = UsdValidation.ValidationContext(validators).Validate(stage)
    result["validationErrors"] = [
        e.GetMessage() for e in findings if e.GetType() == UsdValidation.ValidationErrorType.Error
    ]
    return result


def frames(path, first, last):
    stage = Usd.Stage.Open(path)
    metres = UsdGeom.GetStageMetersPerUnit(stage)
    z_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    result = {
        "startTimeCode": stage.GetStartTimeCode() if stage.HasAuthoredTimeCodeRange() else None,
        "endTimeCode": stage.GetEndTimeCode() if stage.HasAuthoredTimeCodeRange() else None,
        "timeCodesPerSecond": stage.GetTimeCodesPerSecond(),
        "frames": [],
    }
    frame = first
    while frame <= last:
        code = Usd.TimeCode(frame)
        cache = UsdGeom.XformCache(code)
        prims, meshes = {}, {}
        for prim in stage.Traverse():
            if prim.IsA(UsdGeom.BasisCurves) or prim.IsA(UsdGeom.Mesh):
                world = cache.GetLocalToWorldTransform(prim)
                points = [world.Transform(Gf.Vec3d(p)) * metres for p in UsdGeom.PointBased(prim).GetPointsAttr().Get(code)]
                kind = meshes if prim.IsA(UsdGeom.Mesh) else prims
                kind[str(prim.GetPath())] = floats((p[0], p[2], -p[1]) if z_up else p for p in points)
        result["frames"].append({"frame": frame, "curves": prims, "meshes": meshes})
        frame += 1
    return result


def blended(path, t0, t1, weight):
    stage = Usd.Stage.Open(path)

    def blend(a, b):
        def parts(m):
            # Factor: m = r * s * r^T * u * t (u: the rotation, r: shear axes; identity here).
            ok, r, s, u, t, p = m.Factor()
            assert ok, "a singular transform"
            return s, u.ExtractRotationQuat(), t
        (sa, qa, ta), (sb, qb, tb) = parts(a), parts(b)
        s = Gf.Vec3d(*[x + (y - x) * weight for x, y in zip(sa, sb)])
        q = Gf.Slerp(weight, qa, qb)
        t = ta + (tb - ta) * weight
        return Gf.Matrix4d().SetScale(s) * Gf.Matrix4d().SetRotate(q) * Gf.Matrix4d().SetTranslate(t)

    result = {"metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage), "upAxis": UsdGeom.GetStageUpAxis(stage), "curves": []}
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        world = Gf.Matrix4d(1)
        chain = []
        p = prim
        while p and not p.IsPseudoRoot():
            chain.append(p)
            p = p.GetParent()
        for p in chain:  # leaf first: row vectors, so the leaf's matrix multiplies first
            if p.IsA(UsdGeom.Xformable):
                x = UsdGeom.Xformable(p)
                local = blend(x.GetLocalTransformation(Usd.TimeCode(t0)), x.GetLocalTransformation(Usd.TimeCode(t1)))
                world = world * local
        points = UsdGeom.BasisCurves(prim).GetPointsAttr().Get(Usd.TimeCode(t0))
        result["curves"].append(
            {"path": str(prim.GetPath()), "world_points": floats(world.Transform(Gf.Vec3d(q)) for q in points)}
        )
    return result


def author_transformed(out):
    """Centimetres, Z up, /World/Hair (translate, rotateXYZ, scale) holding two curve prims, one
    time-sampled, plus a mesh to skip; written by pxr's own text exporter."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(2)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    world.AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    hair = UsdGeom.Xform.Define(stage, "/World/Hair")
    hair.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    hair.AddRotateXYZOp().Set(Gf.Vec3f(10, 20, 30))
    hair.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    hair.GetPrim().SetCustomDataByKey("coif:note", "dictionary metadata the reader must skip")
    UsdGeom.Mesh.Define(stage, "/World/Head").CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])

    a = UsdGeom.BasisCurves.Define(stage, "/World/Hair/Strands")
    a.CreateTypeAttr(UsdGeom.Tokens.linear)
    a.CreateCurveVertexCountsAttr([3, 2])
    frames = {
        1: [(0, 0, 0), (0, 0, 1), (0, 0.5, 2), (1, 0, 0), (1, 0, 1.5)],
        2: [(0, 0, 0), (0.25, 0, 1), (0.5, 0.5, 2), (1, 0, 0), (1.25, 0, 1.5)],
    }
    for t, pts in frames.items():
        a.GetPointsAttr().Set(Vt.Vec3fArray(pts), t)
    a.CreateWidthsAttr([0.01])
    a.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    color = UsdGeom.PrimvarsAPI(a).CreatePrimvar(
        "displayColor", Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.uniform
    )
    color.Set([(0.5, 0.25, 0.125), (0.75, 0.5, 0.25)])
    color.SetIndices(Vt.IntArray([1, 0]))
    wet = UsdGeom.PrimvarsAPI(a).CreatePrimvar("wetness", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
    wet.Set([0.1, 0.2, 0.3, 0.4, 0.5])
    clump = UsdGeom.PrimvarsAPI(a).CreatePrimvar(
        "clump", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.uniform, elementSize=2
    )
    clump.Set([1, 2, 3, 4])

    b = UsdGeom.BasisCurves.Define(stage, "/World/Hair/Guides")
    b.CreateTypeAttr(UsdGeom.Tokens.linear)
    b.CreateCurveVertexCountsAttr([2])
    b.CreatePointsAttr([(2, 0, 0), (2, 1, 1)])
    b.CreateWidthsAttr([0.02, 0.03])
    b.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    color_b = UsdGeom.PrimvarsAPI(b).CreatePrimvar(
        "displayColor", Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.constant
    )
    color_b.Set([(1, 0, 0)])
    wet_b = UsdGeom.PrimvarsAPI(b).CreatePrimvar("wetness", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
    wet_b.Set([0.6, 0.7])
    clump_b = UsdGeom.PrimvarsAPI(b).CreatePrimvar(
        "clump", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.uniform, elementSize=2
    )
    clump_b.Set([5, 6])
    guide = UsdGeom.PrimvarsAPI(b).CreatePrimvar("groom_guide", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.uniform)
    guide.Set([1])
    text = stage.GetRootLayer().ExportToString()
    header, body = text.split("\n", 1)
    with open(out, "w") as f:
        f.write(f"{header}\n# authored by usd-core for coif's tests\n{body}")


def author_composed(folder):
    """payload.usda holds two variants of a curve; stage.usda references it and selects one."""
    payload = Usd.Stage.CreateNew(f"{folder}/payload.usda")
    UsdGeom.SetStageMetersPerUnit(payload, 1.0)
    root = UsdGeom.Xform.Define(payload, "/Asset")
    payload.SetDefaultPrim(root.GetPrim())
    variants = root.GetPrim().GetVariantSets().AddVariantSet("length")
    for name, tip in (("short", 1.0), ("long", 3.0)):
        variants.AddVariant(name)
        variants.SetVariantSelection(name)
        with variants.GetVariantEditContext():
            c = UsdGeom.BasisCurves.Define(payload, "/Asset/Strands")
            c.CreateTypeAttr(UsdGeom.Tokens.linear)
            c.CreateCurveVertexCountsAttr([2])
            c.CreatePointsAttr([(0, 0, 0), (0, tip, 0)])
            c.CreateWidthsAttr([0.001, 0.001])
    variants.SetVariantSelection("short")
    payload.GetRootLayer().Save()
    stage = Usd.Stage.CreateNew(f"{folder}/stage.usda")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    groom = stage.DefinePrim("/Groom")
    groom.GetReferences().AddReference("./payload.usda")
    stage.SetDefaultPrim(groom)
    stage.GetRootLayer().Save()


def flatten(source, target, variants):
    stage = Usd.Stage.Open(source)
    stage.SetEditTarget(stage.GetSessionLayer())
    for spec in variants:
        prim_path, _, assignment = spec.rpartition(":") if spec.startswith("/") else ("", "", spec)
        set_name, _, variant = assignment.partition("=")
        prims = [stage.GetPrimAtPath(prim_path)] if prim_path else list(stage.Traverse())
        for prim in prims:
            if set_name in prim.GetVariantSets().GetNames():
                prim.GetVariantSets().GetVariantSet(set_name).SetVariantSelection(variant)
    if not stage.Export(target):
        sys.exit(f"pxr could not flatten {source}")


def batch(jobs_file):
    with open(jobs_file) as f:
        jobs = json.load(f)
    for job in jobs:
        if job[0] == "export":
            if not Sdf.Layer.FindOrOpen(job[1]).Export(job[2]):
                sys.exit(f"pxr could not export {job[1]}")
        elif job[0] == "flatten":
            flatten(job[1], job[2], job[3:])
        else:
            sys.exit(f"unknown job {job[0]}")


if __name__ == "__main__":
    command, target = sys.argv[1], sys.argv[2]
    if command == "dump":
        time = float(sys.argv[4]) if len(sys.argv) > 4 and sys.argv[3] == "--time" else None
        json.dump(dump(target, time), sys.stdout)
    elif command == "frames":
        json.dump(frames(target, float(sys.argv[3]), float(sys.argv[4])), sys.stdout)
    elif command == "blended":
        json.dump(blended(target, *(float(a) for a in sys.argv[3:6])), sys.stdout)
    elif command == "author-transformed":
        author_transformed(target)
    elif command == "author-composed":
        author_composed(target)
    elif command == "batch":
        batch(target)
    elif command == "export":
        if not Sdf.Layer.FindOrOpen(target).Export(sys.argv[3]):
            sys.exit(f"pxr could not export {target}")
    else:
        sys.exit(f"unknown command {command}")
