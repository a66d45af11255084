"""Objects: the label image, per-object measurements, touching objects kept apart, metrics.

measure   find_objects, the label image and the regionprops-style table
split     split_touching: objects that touch, cut apart, stage by stage per object:
  arcs      stage 0: the outline's arcs grouped into ellipses
  necks     stage 1: necks of the distance to the outline
  corners   stage 2: cuts between concave corners (and the polygon cut every stage uses)
  contrast  stage 3: a bright object touching a dim one
  shapes    what the stages judge parts by: blobs, hull depth, ellipse fits
metrics   instance matching (IoU) and F1 against a ground-truth label image
"""

from activecontour.objects.measure import find_objects, label_image, measure, polygon_moments
from activecontour.objects.split import split_touching

__all__ = ["find_objects", "label_image", "measure", "polygon_moments", "split_touching"]
