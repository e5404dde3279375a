import csv
import os
from pathlib import Path

import pytest

# The repository's reference files (validation/reference), or ELLIPACK_REFERENCE_DIR as the
# Rust test kit reads it.
REFERENCE = Path(
    os.environ.get("ELLIPACK_REFERENCE_DIR")
    or Path(__file__).resolve().parents[2] / "validation" / "reference"
)


def read_reference(name):
    path = REFERENCE / name
    if not path.exists():
        pytest.fail(f"reference file {path} is missing (set ELLIPACK_REFERENCE_DIR)")
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
