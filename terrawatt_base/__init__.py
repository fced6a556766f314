"""The house's groundwork, shared by every package: errors, validation, atomic files, bounded readers, the dask client.

Nothing here knows about maps, robots or routes:

- :mod:`~terrawatt_base.errors`: the one exception hierarchy (``TerrawattError`` and its
  subclasses, each also the builtin it resembles) and the warning classes; ``terrain``,
  ``energy`` and ``planner`` re-export them;
- :mod:`~terrawatt_base.checks`: validation of parameters (``check_real``, ``check_int``, ...)
  and numbers for people (``fmt_number``, ``plain_repr``);
- :mod:`~terrawatt_base.atomic`: files written atomically, outputs checked before any work;
- :mod:`~terrawatt_base.containers` and :mod:`~terrawatt_base.formats`: zip / ``.npz`` /
  ``.npy`` containers read within a memory budget, versioned ``.npz`` files;
- :mod:`~terrawatt_base.dask_client`: a dask.distributed client with deadlines;
- :mod:`~terrawatt_base.plot_target`: where a figure goes (a file, or the caller's axes) and the
  figure made for a file (matplotlib's object API, never pyplot);
- :mod:`~terrawatt_base.figure_file`: a report's figure drawn, or a ``FigureWarning`` when it fails.
- :mod:`~terrawatt_base.answer`: an answer's files and figures written into a folder, its markdown
  tables and fixed-point numbers.
"""

#: Nothing is named here: import from the modules (``from terrawatt_base.errors import ...``).
__all__: list[str] = []
