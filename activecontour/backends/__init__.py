"""The backends: each minimises the Chan-Vese functional (6.38) over its own representation.

polygon     the book's H^1 gradient flow of a polygon: :mod:`activecontour.flow` (to move here)
levelset    a level set over the pixel grid: redistancing, zero set, scheme and driver
labelfield  N regions on the pixel grid by threshold dynamics (``n_regions > 2``)
"""
