"""The unjam binary the script tests drive: $UNJAM (ctest sets it to the build's own), else
build/release/unjam; tests that need it are skipped when it is missing (`requires_unjam`)."""

import os
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UNJAM = os.path.abspath(os.environ.get("UNJAM") or os.path.join(REPO, "build", "release", "unjam"))

requires_unjam = unittest.skipUnless(
    os.path.isfile(UNJAM) and os.access(UNJAM, os.X_OK),
    f"{UNJAM} is missing: build it first (cmake --build build/release -j2)")

