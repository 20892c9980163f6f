"""Pictures: a plan and its verification, the paper's figures, and maps of a track.

- :mod:`~profileopt.viz.plots`: a profile and its verification;
- :mod:`~profileopt.viz.figures`: the paper's Figs. 1, 5 and 6;
- :mod:`~profileopt.viz.maps`: a track over its terrain map.
"""
