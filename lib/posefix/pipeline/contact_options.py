"""The contact solver's options (config ``contact``), shared by the stages that build one (verify, repair_contact)."""

from dataclasses import asdict

from posefix.mesh.contact_solver import ContactSettings


def add_contact_options(parser):
    """Add ``--dhat``, ``--touching``, ``--smoothing``, ``--tolerance`` and ``--max-iterations`` (defaults: the
    library's :class:`ContactSettings`) to ``parser`` (argparse.ArgumentParser)."""
    contact = ContactSettings()
    group = parser.add_argument_group("contact solver (config contact; lengths / bbox diagonal)")
    group.add_argument("--dhat", type=float, default=contact.dhat, help="barrier activation distance")
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
    settings = ContactSettings(args.dhat, args.touching, args.smoothing, args.tolerance, args.max_iterations)
    return settings, asdict(settings)
