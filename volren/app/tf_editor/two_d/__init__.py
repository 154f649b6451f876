"""The 2D transfer-function editor: the panel and the canvas drawing the widgets over the joint
histogram."""
