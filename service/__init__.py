"""demcal's REST service, job queue, campaigns and CLI."""
