"""Work with files off the GUI thread and the widgets around it: loading in the background,
screenshots, recent files, the screenshot dialog (Qt)."""
