"""Files at the base of mien: paths or streams (atomic writes), the clip container, hashing, data tables.

Every module above imports from here; nothing here imports from above. Needs numpy only.
"""
