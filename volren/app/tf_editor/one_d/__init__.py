"""The 1D transfer-function editor: the panel, and the opacity curve and colour bar it stacks on
one shared value axis (`point_canvas`)."""
