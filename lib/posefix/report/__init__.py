"""Reports: the summary entries of a library, its tables, the figures and the offscreen rasterizer."""
