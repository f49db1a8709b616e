"""The installed flexbody package reads a body file: prints its version and how many modes the file has."""
import sys

import flexbody

print(flexbody.__version__, len(flexbody.read_body(sys.argv[1]).frequencies_hz))
