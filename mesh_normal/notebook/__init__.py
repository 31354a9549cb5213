"""The library in a notebook: the reports' HTML (:mod:`~mesh_normal.notebook.html`, what
Jupyter shows for a :class:`~mesh_normal.MeshReport` or a point report) and ``mn.show``, a
Plotly figure of a mesh or a cloud (:mod:`~mesh_normal.notebook.show`, with the ``show`` extra:
``pip install mesh-normal[show]``).

Nothing in the geometry, the readers or the reports imports this package at import time: the
reports' ``_repr_html_`` imports :mod:`~mesh_normal.notebook.html` when a notebook asks.
"""
