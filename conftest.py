"""The repository's test-session rules (skip allow-list, per-session caches) for tests/ and
plugins/: see tests/session_policy.py."""

pytest_plugins = ["tests.session_policy"]
