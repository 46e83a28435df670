"""Numba kernels for Monte Carlo localization, one module per job.

- `pieces`: per-particle pieces the kernels are built from (move a pose,
  a sensor's pose, a cone table's entry), inlined where they are used
- `steps`: the fused step on a cone table (predict, weigh, normalise,
  estimate), one body per sensor model, serial and threaded
- `cone_table`: building a cone table and looking readings up in it
- `kld`: KLD-sampling's stopping rule

Every kernel takes contiguous arrays and scalars only; random numbers are
drawn by the caller's ``numpy.random.Generator`` and handed in, so a seed
reproduces a run. Each kernel has a plain NumPy reference in
``tests/naive_mcl.py`` that the tests compare it with. Units: metres,
radians; cone tables hold millimetres (uint16).
"""
