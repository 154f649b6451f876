"""The main window (Qt), one module per concept: the wiring (`main_window`), the docks, opening
files, saving scenes, screenshots, the renderer in use, and drag and drop."""
