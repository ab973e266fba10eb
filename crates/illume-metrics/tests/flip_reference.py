#!/usr/bin/env python3
"""Mean FLIP of the reference implementation for the fixtures of flip_reference.rs.

Usage (see the module docs of tests/flip_reference.rs):

    pip install flip-evaluator==1.7
    ILLUME_FLIP_FIXTURE_DIR=/tmp/flip-fixtures \
      cargo test -p illume-metrics --test flip_reference -- --ignored write_flip_fixtures
    python3 crates/illume-metrics/tests/flip_reference.py /tmp/flip-fixtures

Each manifest line is `name kind reference test width height ppd tone_mapper`
(`-` = default). LDR cases are 8-bit sRGB PNGs, loaded by the package and evaluated
with LDR-FLIP (the package converts sRGB to linear). HDR cases are raw little-endian
float32 linear RGB (the same floats as the EXRs the Rust test reads; the package's
EXR loader crashes on those files), evaluated with HDR-FLIP. Prints Rust source for
the EXPECTED table: per case the mean error, the largest per-pixel error, and the
per-pixel errors at SAMPLE_PIXELS (x, y), which must match SAMPLE_PIXELS in the test,
and for HDR-FLIP the exposure bracket (start, stop, count) chosen automatically.
"""
import os
import sys

import flip_evaluator as flip
import numpy as np


SAMPLE_PIXELS = [(0, 0), (31, 20), (63, 63), (10, 50)]


def main(directory):
    print("const EXPECTED: &[Expected] = &[")
    with open(os.path.join(directory, "manifest.txt")) as manifest:
        for line in manifest:
            name, kind, ref, test, width, height, ppd, tone_mapper = line.split()
            parameters = {}
            if ppd != "-":
                parameters["ppd"] = float(ppd)
            if tone_mapper != "-":
                parameters["tonemapper"] = tone_mapper
            if kind == "ldr":
                reference = flip.load(os.path.join(directory, ref))
                test_image = flip.load(os.path.join(directory, test))
            else:
                shape = (int(height), int(width), 3)
                reference = np.fromfile(os.path.join(directory, ref), dtype="<f4").reshape(shape)
                test_image = np.fromfile(os.path.join(directory, test), dtype="<f4").reshape(shape)
            error_map, mean, used = flip.evaluate(
                reference, test_image, kind.upper(), applyMagma=False, parameters=parameters
            )
            samples = ", ".join(f"{error_map[y, x, 0]:.7f}" for x, y in SAMPLE_PIXELS)
            if kind == "hdr":
                exposures = (
                    f"Some(({used['startExposure']:.6f}, {used['stopExposure']:.6f}, "
                    f"{used['numExposures']}))"
                )
            else:
                exposures = "None"
            print(
                f'    Expected {{ name: "{name}", mean: {mean:.7f}, max: {error_map.max():.7f}, '
                f"samples: [{samples}], exposures: {exposures} }},"
            )
    print("];")


if __name__ == "__main__":
    main(sys.argv[1])
