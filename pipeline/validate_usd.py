#!/usr/bin/env python3
"""Validates a USD stage with usd-core's UsdValidation (every registered validator).

  validate_usd.py STAGE [--json]

Prints each finding as "SEVERITY validator: message [sites]". Exit codes: 0 no errors (warnings
are printed but allowed), 1 at least one error, 2 the stage cannot be opened, 3 usd-core (pxr)
is not importable by this Python.
"""
import argparse
import json
import sys

try:
    from pxr import Usd, UsdValidation
except ImportError as error:
    print(f"validate_usd: usd-core (pxr) is not importable by {sys.executable}: {error}", file=sys.stderr)
    sys.exit(3)


def validate(path):
    """The findings of every registered validator on the stage at `path`."""
    stage = Usd.Stage.Open(path)
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    context = UsdValidation.ValidationContext(validators)
    findings = []
    for error in context.Validate(stage):
        sites = []
        for site in error.GetSites():
            if site.IsPrim() or site.IsProperty():
                sites.append(str(site.GetPrim().GetPath() if site.IsPrim() else site.GetProperty().GetPath()))
        findings.append(
            {
                "severity": str(error.GetType()).rsplit(".", 1)[-1],
                "is_error": error.GetType() == UsdValidation.ValidationErrorType.Error,
                "validator": error.GetValidator().GetMetadata().name if error.GetValidator() else "",
                "name": str(error.GetName()),
                "message": error.GetMessage(),
                "sites": sites,
            }
        )
    return findings


def main(argv=None):
    parser = argparse.ArgumentParser(description="Validate a USD stage with UsdValidation.")
    parser.add_argument("stage")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    try:
        findings = validate(args.stage)
    except Exception as error:
        print(f"validate_usd: {args.stage}: cannot open the stage: {error}", file=sys.stderr)
        return 2
    errors = sum(1 for f in findings if f["is_error"])
    if args.json:
        print(json.dumps({"stage": args.stage, "errors": errors, "findings": findings}, indent=2))
    else:
        for f in findings:
            sites = f" [{', '.join(f['sites'])}]" if f["sites"] else ""
            print(f"{f['severity']} {f['validator'] or f['name']}: {f['message']}{sites}")
        print(f"{args.stage}: {errors} error(s), {len(findings) - errors} other finding(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
