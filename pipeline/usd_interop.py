#!/usr/bin/env python3
"""USD interop for coif through usd-core (pxr).

coif reads and writes USD text (.usda) itself. Everything else goes through this script:

  usd_interop.py flatten INPUT OUTPUT.usda [--variant [PRIM_PATH:]SET=NAME ...]
      Composes any stage usd-core opens (.usdc, .usdz, .usda with sublayers, references,
      payloads, variants) and writes it as one flattened .usda that coif reads.
      --variant selects a variant before flattening: SET=NAME on every prim that has the
      variant set SET, or /Prim/Path:SET=NAME on one prim. Repeat for several sets.

  usd_interop.py export INPUT.usda OUTPUT.(usdc|usda|usdz)
      Writes a layer in another USD file format (crate binary, text, or a usdz package).

Exit codes: 0 done, 2 the input cannot be read (usd-core raised while opening, composing or
flattening it) or an option is wrong, 3 usd-core (pxr) is not importable by this Python, 4 out of
memory (coif runs this script under its --max-memory), 1 anything else (such as an output that
cannot be written).
"""
import argparse
import os
import sys
import tempfile
import time

try:
    from pxr import Sdf, Usd, UsdUtils
except ImportError as error:  # coif turns this exit code into a "usd-core is missing" message
    print(f"usd_interop: usd-core (pxr) is not importable by {sys.executable}: {error}", file=sys.stderr)
    sys.exit(3)


class BadInput(Exception):
    """The input stage or an option is unusable (exit code 2)."""


def open_stage(path):
    if not os.path.exists(path):
        raise BadInput(f"{path}: no such file")
    try:
        stage = Usd.Stage.Open(path)
    except MemoryError:
        raise
    except Exception as error:  # pxr raises Tf.ErrorException with the parser's message
        raise BadInput(f"{path}: usd-core cannot open the stage: {error}") from error
    if stage is None:
        raise BadInput(f"{path}: usd-core cannot open the stage")
    return stage


def select_variant(stage, spec):
    prim_path, _, assignment = spec.rpartition(":") if spec.startswith("/") else ("", "", spec)
    set_name, sep, variant = assignment.partition("=")
    if not sep or not set_name or not variant:
        raise BadInput(f"--variant {spec!r}: expected [PRIM_PATH:]SET=NAME")
    if prim_path:
        prim = stage.GetPrimAtPath(prim_path)
        if not prim:
            raise BadInput(f"--variant {spec!r}: no prim at {prim_path}")
        prims = [prim]
    else:
        prims = [p for p in stage.Traverse() if set_name in p.GetVariantSets().GetNames()]
    chosen = 0
    for prim in prims:
        variant_set = prim.GetVariantSets().GetVariantSet(set_name)
        names = variant_set.GetVariantNames()
        if set_name not in prim.GetVariantSets().GetNames():
            raise BadInput(f"--variant {spec!r}: {prim.GetPath()} has no variant set {set_name!r}")
        if variant not in names:
            raise BadInput(
                f"--variant {spec!r}: {prim.GetPath()} has no variant {variant!r} in set {set_name!r} "
                f"(it has {', '.join(names)})"
            )
        variant_set.SetVariantSelection(variant)
        chosen += 1
    if chosen == 0:
        raise BadInput(f"--variant {spec!r}: no prim has a variant set {set_name!r}")


def flatten(args):
    try:
        layer = flattened(args)
    except (BadInput, MemoryError):
        raise
    except Exception as error:  # Tf.ErrorException (a corrupt value or block), text not UTF-8, ...
        raise BadInput(f"{args.input}: usd-core cannot read the stage: {error}") from error
    if not layer.Export(args.output, args={"format": "usda"}):
        raise RuntimeError(f"{args.output}: usd-core could not write the flattened stage")


def flattened(args):
    """The input's stage, variants selected, flattened into an anonymous layer."""
    stage = open_stage(args.input)
    # Selections go to the session layer, so the user's files are never modified.
    stage.SetEditTarget(stage.GetSessionLayer())
    for spec in args.variant:
        select_variant(stage, spec)
    # Instanceable prims flatten to references to their prototypes, arcs coif's reader of the
    # flattened layer does not take: make each instance (nested ones in turn) a plain prim.
    while True:
        instances = [prim for prim in stage.Traverse() if prim.IsInstance()]
        if not instances:
            break
        for prim in instances:
            prim.SetInstanceable(False)
    return stage.Flatten()


# 1980-01-01 00:00 local time, the earliest time a zip entry holds, as reproducible zips use.
ZIP_EPOCH = time.mktime((1980, 1, 1, 0, 0, 0, 0, 1, -1))


def export(args):
    layer = Sdf.Layer.FindOrOpen(args.input)
    if layer is None:
        raise BadInput(f"{args.input}: usd-core cannot open the layer")
    extension = os.path.splitext(args.output)[1].lower()
    if extension in (".usdc", ".usda", ".usd"):
        file_format = {".usdc": "usdc", ".usda": "usda", ".usd": "usdc"}[extension]
        if not layer.Export(args.output, args={"format": file_format}):
            raise RuntimeError(f"{args.output}: usd-core could not write the layer")
    elif extension == ".usdz":
        with tempfile.TemporaryDirectory() as folder:
            crate = os.path.join(folder, os.path.splitext(os.path.basename(args.output))[0] + ".usdc")
            if not layer.Export(crate, args={"format": "usdc"}):
                raise RuntimeError(f"{crate}: usd-core could not write the layer")
            # The package's entry carries the file's modification time (as local DOS time): the
            # clock's would make every export other bytes.
            os.utime(crate, (ZIP_EPOCH, ZIP_EPOCH))
            if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(crate), args.output):
                raise RuntimeError(f"{args.output}: usd-core could not write the usdz package")
    else:
        raise BadInput(f"{args.output}: unknown USD extension {extension!r} (use .usdc, .usda or .usdz)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    flat = commands.add_parser("flatten", help="compose any USD stage into one flattened .usda")
    flat.add_argument("input")
    flat.add_argument("output")
    flat.add_argument("--variant", action="append", default=[], metavar="[PRIM_PATH:]SET=NAME")
    out = commands.add_parser("export", help="write a layer as .usdc, .usda or .usdz")
    out.add_argument("input")
    out.add_argument("output")
    args = parser.parse_args(argv)
    try:
        {"flatten": flatten, "export": export}[args.command](args)
    except BadInput as error:
        print(f"usd_interop: {error}", file=sys.stderr)
        return 2
    except MemoryError:  # also a std::bad_alloc in usd-core
        print("usd_interop: out of memory", file=sys.stderr)
        return 4
    except Exception as error:
        print(f"usd_interop: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
