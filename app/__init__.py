"""The front ends built on the library: the ``activecontour`` command line and the viewer.

The source folder is ``app/``; it installs as the package ``activecontour_app`` (a bare ``app``
would clash with other projects).  Its modules import each other relatively, so both names
work: ``python -m app`` in the source tree, ``python -m activecontour_app`` once installed.
"""
