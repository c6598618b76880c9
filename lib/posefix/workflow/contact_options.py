"""The contact solver's options (config ``contact``), shared by the stages that build one (verify, repair_contact)."""

from dataclasses import asdict

from posefix.mesh.contact_solver import ContactSettings


def add_contact_options(parser):
    """Add ``--dhat``, ``--dhat-min``, ``--touching``, ``--smoothing``, ``--tolerance`` and ``--max-iterations`` (defaults: the
    library's :class:`ContactSettings`) to ``parser`` (argparse.ArgumentParser)."""
    contact = ContactSettings()
    group = parser.add_argument_group("contact solver (config contact; lengths / bbox diagonal)")
    group.add_argument("--dhat", type=float, default=contact.dhat,
                       help="largest barrier activation distance (half the reference's clearance when smaller)")
    group.add_argument("--dhat-min", type=float, default=contact.dhat_min,
                       help="smallest barrier activation distance (parts closer at rest feel the barrier)")
    group.add_argument("--touching", type=float, default=contact.touching,
                       help="pairs of the reference closer than this are tolerated (touching at rest)")
    group.add_argument("--smoothing", type=float, default=contact.smoothing,
                       help="smoothing length of the bi-Laplacian term")
    group.add_argument("--tolerance", type=float, default=contact.tolerance,
                       help="Newton stops when its step moves no vertex farther than this")
    group.add_argument("--max-iterations", type=int, default=contact.max_iterations,
                       help="Newton iterations at most per solve")


def contact_settings(args):
    """(ContactSettings, dict of its fields) from the options of :func:`add_contact_options`."""
    settings = ContactSettings(dhat=args.dhat, dhat_min=args.dhat_min, touching=args.touching,
                               smoothing=args.smoothing, tolerance=args.tolerance, max_iterations=args.max_iterations)
    return settings, asdict(settings)
