"""The repository's test-session rules (skip allow-list, per-session caches) for tests/ and
plugins/: see tests/session_policy.py; markers derived from what a test uses: tests/markers.py."""

pytest_plugins = ["tests.session_policy", "tests.markers"]
