"""Imaging: the image as (6.38) reads it.

normalize   intensities onto [0, 1] (the image's range, its dtype's, or as given), colour modes
frame       the working frame the flow computes in
tables      the bilinear image and its row-antiderivative tables (Green's theorem)
noise       the noise level and the default mu it implies
roi         the image domain D restricted to a box, a mask or a neighbourhood of the init
strips      block means and blurs made a strip of rows at a time, exactly as the whole image's
"""
