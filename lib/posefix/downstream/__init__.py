"""The downstream check (S0 §5): example-driven discrete-shell deformation solved by Gauss–Newton
towards the original and the repaired pose."""
