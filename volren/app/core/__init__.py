"""The app's Qt-free core: what is shown, and the logic behind the widgets, testable without Qt.

Nothing here imports PyQt5, directly or through what it imports (tests/test_import_rules.py).
"""
