"""flexmvm: contact and impact of flexible bodies with the multi-variable method.

Stages follow the data flow (docs/architecture.md):
mesh -> fe -> reduction -> bodies -> constraints/contact -> integrate -> results
-> metrics -> studies -> plots / cli.
"""

__version__ = "0.1.0"
