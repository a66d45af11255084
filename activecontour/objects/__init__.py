"""Objects: the label image, per-object measurements, touching objects kept apart, metrics.

measure   find_objects, the label image and the regionprops-style table
split     split_touching: objects that touch, cut along their necks
metrics   instance matching (IoU) and F1 against a ground-truth label image
"""

from activecontour.objects.measure import find_objects, label_image, measure, polygon_moments
from activecontour.objects.split import split_touching

__all__ = ["find_objects", "label_image", "measure", "polygon_moments", "split_touching"]
