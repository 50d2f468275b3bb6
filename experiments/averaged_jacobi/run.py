import sys, os
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
if os.environ.get("AJ", "1") == "1":
    import avgjacobi
    avgjacobi.install()
from ti_golf.cli.main import main
sys.exit(main(sys.argv[1:]))
