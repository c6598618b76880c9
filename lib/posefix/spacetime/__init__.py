"""S0, pose correction by space-time integration (Martinez Esturo, Rössl, Theisel, EG 2011).

Key frames by gradient-space interpolation, the classification of the constrained vertices
``V_C``, space-time constraints, the greedy RBF fit of the space-time vector field with blocked
factorization updates, and the RK45 integration of every vertex through it (numpy and OpenCL).
"""
