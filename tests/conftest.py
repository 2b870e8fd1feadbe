import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from medax.geometry.region_io import sample_regions_path  # noqa: E402


@pytest.fixture(scope="session")
def regions_spec() -> dict:
    """The raw JSON of the shipped sample regions."""
    return json.loads(sample_regions_path().read_text())
