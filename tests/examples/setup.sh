# Sourced by the example tests: Debian's python3 with the modules named in $need (else exit 77, skipped), and a
# scratch folder $dir removed on exit.
py=/usr/bin/python3
if ! "$py" -c "import $need" 2>/dev/null; then
  echo "skipped: $py lacks one of $need (Debian: apt-get install python3-h5py python3-pandas)"
  exit 77
fi
dir=$(mktemp -d /tmp/flume_test_examples.XXXXXX)
trap 'rm -rf "$dir"' EXIT
