"""tetrapage: exact collision detection in huge CAD models, paged from disk.

    import tetrapage
    tetrapage.preprocess(["assembly.step"], "assembly.tpi")
    index = tetrapage.Index("assembly.tpi", memory="256M")
    tool = index.object(tetrapage.read_mesh("tool.stl"))
    hits = tool.collides(poses)          # (K, 7) tx, ty, tz, qw, qx, qy, qz -> (K,) bool

Queries release the GIL: one Index may be shared by threads, each with its own FlyingObject.
Errors are tetrapage.Error: IoError (also an OSError), FormatError, InputError (also a
ValueError). docs/USAGE.md, "From Python", has a complete script.
"""

from ._tetrapage import *  # noqa: F401,F403
from ._tetrapage import __version__  # noqa: F401
