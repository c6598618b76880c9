"""S4: volumetric shape editing on a coarse tetrahedral mesh (Stoll, de Aguiar, Theobalt, Seidel 2007)."""
