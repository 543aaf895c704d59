# Sourced by scripts that need the Debian mirror this machine's apt uses (debootstrap): never a
# host name written in the repo (ground rule 7), always the one configured here at run time.
# The Debian mirror this machine's apt uses for bookworm: deb822 .sources files first (Debian 12
# machines may have only /etc/apt/sources.list.d/debian.sources), then one-line .list files. Reads
# only files that exist, and always succeeds: "no mirror found" is reported by the caller, by name.
apt_mirror() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    # Stanzas are separated by blank lines; a field may continue on indented lines; # comments.
    awk 'function flush() {
           if (enabled != "no" && types ~ /(^|[ \t])deb([ \t]|$)/ && suites ~ /(^|[ \t])bookworm([ \t]|$)/ && uris != "") {
             sub(/^[ \t]+/, "", uris); split(uris, u, /[ \t]+/); print u[1] }
           uris = suites = types = enabled = ""; last = "" }
         /^[ \t]*#/ { next }
         /^[ \t]*$/ { flush(); next }
         /^[ \t]/ { if (last == "uris") uris = uris " " $0; if (last == "suites") suites = suites " " $0; next }
         { key = tolower($0); sub(/:.*/, "", key); val = $0; sub(/^[^:]*:[ \t]*/, "", val); last = key
           if (key == "uris") uris = val; else if (key == "suites") suites = val
           else if (key == "types") types = val; else if (key == "enabled") enabled = tolower(val) }
         END { flush() }' "$f" | sed -E 's/^[ \t]+//'
  done
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    sed -nE 's/^deb[ \t]+(\[[^]]*\][ \t]+)?([^ \t]+)[ \t]+bookworm([ \t].*)?$/\2/p' "$f"
  done
  return 0
}
