"""Shared test set-up: the tests folder is importable, for its reference helpers."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

# the cache of compiled user-defined specs (moveability.mechanisms.custom): one per test
# process, not the user's
if "MOVEABILITY_CACHE_DIR" not in os.environ:
    import atexit
    import shutil
    import tempfile

    os.environ["MOVEABILITY_CACHE_DIR"] = tempfile.mkdtemp(prefix="moveability-cache-")
    atexit.register(shutil.rmtree, os.environ["MOVEABILITY_CACHE_DIR"], ignore_errors=True)
