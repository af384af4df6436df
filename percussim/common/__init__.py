"""percussim.common: what the API and the workers share. The settings (`settings`), the job and
sweep records in a database (`database`, its schema's `migrations`), the results store on disk
(`store`), where jobs are queued (`broker`, and `queue_files`, the embedded queue's transport),
and the counters behind `/metrics` (`metrics`). `percussim.service` (the API) and
`percussim.worker` (the Celery app and its tasks) both stand on it; neither imports the other.
"""
