"""Interactive apps of vidcap (the ``ui`` extra: trame, vuetify 3, pyvista's trame views).

* :mod:`vidcap.ui.view`: ``vidcap view`` - a BVH skeleton over a ground grid or a C3D marker
  cloud (with fitted joint centres), in a window or offscreen to a PNG;
* :mod:`vidcap.ui.annotate`: ``vidcap annotate`` - the web page for depth directions,
  orientation and occluded joints, with a live 3D pose and a Review tab;
* :mod:`vidcap.ui.session`: the state behind that page (stage results, annotations, re-lifting),
  usable without a browser;
* :mod:`vidcap.ui.render`: the pictures the page shows.

The library never imports this package; the commands import it lazily.
"""
