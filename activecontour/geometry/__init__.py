"""Geometry: closed polygons, P1 elements, crossings, rasterising, partitions, regions.

curve       the 1-D geometry of section 6.5 (tangent, normal, curvature), stacked curves
fem         P1 mass and stiffness matrices on a closed polygon (6.39)
topology    crossings and their repair, winding numbers, nucleation sites
raster      curves <-> masks
partition   boundaries between the classes of a label image (N regions)
regions     hole grouping and shapely region operations
hull        the convex hull of a point set (compiled, no scipy.spatial)
"""
