"""Test helper: shots (cameras, lights, a few hair tufts) authored by usd-core (pxr), and what pxr's
own camera model predicts about them, as JSON on stdout.

  pxr_shot.py camera OUT WIDTH HEIGHT   Z-up centimetre stage: a rolled, nested camera and hair
                                        tufts; prints the pixel pxr projects each tuft's centre to
                                        for a WIDTH x HEIGHT image (aperture fitted to the aspect)
  pxr_shot.py light OUT KIND SIDE       Z-up centimetre stage: a camera looking at the origin and
                                        one light (KIND distant or sphere) placed by pxr towards
                                        SIDE (+1 or -1 along the stage's X); prints on which side
                                        of the image (+1 right, -1 left) pxr projects the light
"""
import json
import sys

from pxr import Gf, Usd, UsdGeom, UsdLux


def new_stage(path):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    return stage


def look_at_camera(stage, path, eye, centre, up):
    camera = UsdGeom.Camera.Define(stage, path)
    view = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(*centre), Gf.Vec3d(*up))
    camera.AddTransformOp().Set(view.GetInverse())
    return camera


def fitted(gf_camera, aspect):
    """The camera with its aperture grown to the image's aspect (CameraUtilFit, which usd-core
    does not ship): the authored window stays whole inside the image."""
    if aspect >= gf_camera.aspectRatio:
        gf_camera.horizontalAperture = gf_camera.verticalAperture * aspect
    else:
        gf_camera.verticalAperture = gf_camera.horizontalAperture / aspect
    return gf_camera


def pixel(frustum, point, width, height):
    """Where pxr's frustum projects a world point, in continuous pixel coordinates (x right,
    y down, the image's corner at 0)."""
    matrix = frustum.ComputeViewMatrix() * frustum.ComputeProjectionMatrix()
    ndc = matrix.Transform(Gf.Vec3d(*point))
    return [(ndc[0] + 1.0) * 0.5 * width, (1.0 - ndc[1]) * 0.5 * height]


def author_camera(path, width, height):
    stage = new_stage(path)
    # The camera sits under a rotated, translated parent, rolled about its view axis.
    rig = UsdGeom.Xform.Define(stage, "/shot/rig")
    rig.AddTranslateOp().Set(Gf.Vec3d(5.0, -3.0, 2.0))
    rig.AddRotateZOp().Set(30.0)
    camera = UsdGeom.Camera.Define(stage, "/shot/rig/cam")
    camera.AddTranslateOp().Set(Gf.Vec3d(10.0, -75.0, 20.0))
    camera.AddRotateXYZOp().Set(Gf.Vec3d(80.0, 12.0, -8.0))
    camera.GetFocalLengthAttr().Set(28.0)
    camera.GetHorizontalApertureAttr().Set(24.0)
    camera.GetVerticalApertureAttr().Set(18.0)
    frustum = fitted(camera.GetCamera(Usd.TimeCode.Default()), width / height).frustum
    # Tufts at points that pxr projects well inside the image: aim along rays through chosen
    # pixels at several depths.
    targets = [(0.5, 0.5, 60.0), (0.22, 0.3, 45.0), (0.8, 0.25, 80.0), (0.3, 0.78, 70.0), (0.75, 0.7, 55.0)]
    inverse = (frustum.ComputeViewMatrix() * frustum.ComputeProjectionMatrix()).GetInverse()
    eye = frustum.GetPosition()
    centres = []
    for fx, fy, depth in targets:
        far = inverse.Transform(Gf.Vec3d(2.0 * fx - 1.0, 1.0 - 2.0 * fy, 0.5))
        direction = (far - eye).GetNormalized()
        centres.append(eye + direction * depth)
    curves = UsdGeom.BasisCurves.Define(stage, "/shot/tufts")
    points, counts = [], []
    # Each tuft: three 1.2 cm strands crossing at its centre along the stage axes, so their
    # coverage is centred on the centre's projection.
    for centre in centres:
        for axis in (Gf.Vec3d(1, 0, 0), Gf.Vec3d(0, 1, 0), Gf.Vec3d(0, 0, 1)):
            points += [centre - axis * 0.6, centre, centre + axis * 0.6]
            counts.append(3)
    curves.GetTypeAttr().Set(UsdGeom.Tokens.linear)
    curves.GetCurveVertexCountsAttr().Set(counts)
    curves.GetPointsAttr().Set([Gf.Vec3f(*p) for p in points])
    curves.GetWidthsAttr().Set([0.4] * len(points))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    stage.GetRootLayer().Save()
    print(json.dumps({"pixels": [pixel(frustum, c, width, height) for c in centres]}))


def author_light(path, kind, side):
    stage = new_stage(path)
    # Coif's sample grooms sit around the origin in metres, Y up: the stage looks at them from
    # the front (coif +Z is this stage's −Y).
    camera = look_at_camera(stage, "/shot/cam", (0.0, -90.0, 5.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    camera.GetFocalLengthAttr().Set(35.0)
    if kind == "distant":
        light = UsdLux.DistantLight.Define(stage, "/shot/key")
        # Rotate the light's −Z (its emission) so it shines from the side, a little above.
        light.AddRotateXYZOp().Set(Gf.Vec3d(0.0, side * 70.0, 0.0))
        light.AddRotateXOp().Set(10.0)
        light.CreateIntensityAttr(50000.0)
        light.CreateAngleAttr(2.0)
        towards = light.ComputeLocalToWorldTransform(Usd.TimeCode.Default()).TransformDir(Gf.Vec3d(0, 0, 1))
        probe = Gf.Vec3d(towards).GetNormalized() * 20.0
    else:
        light = UsdLux.SphereLight.Define(stage, "/shot/bulb")
        light.AddTranslateOp().Set(Gf.Vec3d(side * 60.0, -20.0, 15.0))
        light.CreateRadiusAttr(5.0)
        light.CreateIntensityAttr(60.0)
        probe = light.ComputeLocalToWorldTransform(Usd.TimeCode.Default()).Transform(Gf.Vec3d(0, 0, 0))
    stage.GetRootLayer().Save()
    frustum = fitted(camera.GetCamera(Usd.TimeCode.Default()), 1.0).frustum
    x = pixel(frustum, probe, 2.0, 2.0)[0] - pixel(frustum, Gf.Vec3d(0, 0, 0), 2.0, 2.0)[0]
    print(json.dumps({"side": 1 if x > 0 else -1}))


if __name__ == "__main__":
    command = sys.argv[1]
    if command == "camera":
        author_camera(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    elif command == "light":
        author_light(sys.argv[2], sys.argv[3], float(sys.argv[4]))
    else:
        sys.exit(f"unknown command {command}")
