"""Response models of the REST API, one module per area; the routers name them in ``response_model``.

Why apart from the routers: the report, diagnosis and history are built by the campaign code as
plain dicts and stored as JSON; these models only describe them, so that the OpenAPI document says
what the page and the CLI read, and a typo in a key is a failing test, not a blank cell.
"""
