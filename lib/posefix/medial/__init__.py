"""S1: skeleton-based variational mesh deformation (Yoshizawa, Belyaev, Seidel 2007)."""
