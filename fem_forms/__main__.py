from fem_forms.cli import entry

entry()
