"""Ground truth for tests, the demo and the benchmarks (and for users' own tests): exactly symmetric
meshes built in code, known deformations, farthest-point landmark pairs and symmetry errors
(``synthetic``, numpy only); surfaces whose true twins are points, not vertices (``surface_truth``); and
symmetric meshes remeshed so that no vertex keeps an exact twin (``remeshing``, with pymeshlab). Outside
the product's floors: nothing in the package imports it."""
