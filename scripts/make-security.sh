#!/usr/bin/env bash
# Makes a TEST public-key infrastructure for usv-fdi's DDS Security (Fast DDS builtin plugins:
# PKI-DH authentication, Access-Permissions access control, AES-GCM-GMAC encryption):
#
#   OUT/ca/ca.pem, ca.key          test CA (ECDSA P-256), identity CA and permissions CA at once
#   OUT/governance.xml, .p7s       config/security/governance.xml, signed with `openssl smime`
#   OUT/<name>/cert.pem, key.pem   identity of each participant, signed by the CA
#   OUT/<name>/permissions.xml,.p7s  its grant (role's rights, see config/security/permissions.xml.in)
#   OUT/<name>/role, vessels       its role and the vessels it is bound to / granted (one a line)
#   OUT/security_profiles.xml      Fast DDS XML participant profiles that enable all three plugins:
#                                    usv_fdi_secure_<name>           builtin transports (SHM+UDPv4)
#                                    usv_fdi_secure_<name>_loopback  UDPv4 on 127.0.0.1 only
#                                    usv_fdi_secure_<name>_unicast   UDPv4, discovery by unicast to
#                                                                    --initial-peers (if given)
#
# Fast DDS 2.9 (Debian bookworm) cannot combine DDS Security with a discovery server (the secure
# discovery server came with Fast DDS 2.10; the 2.9 server aborts on an assertion in
# SecurityManager::encode_rtps_message when given security properties). A secure fleet without
# multicast therefore uses the _unicast profiles: SIMPLE discovery sent to a fixed list of
# addresses (shore and vessels), see docker/README.md.
#
# Usage: scripts/make-security.sh OUT [options]
#   --identity ROLE:NAME[:VESSELS]
#                          add an identity (repeatable); ROLE is vessel, sensors, shore or observer.
#                          VESSELS ties it to vessels (MMSIs, 1..999999999), and every right of a
#                          vessel-bound role is confined to the vessel's partition PREFIXvessel-<MMSI>:
#                            vessel:NAME:MMSI     the sidecar of that one vessel: publishes its fault
#                                                 events and status, reads its INS, rudder, speed, acks and
#                                                 its own fault events (to spot a second writer),
#                                                 only in its own partition (required: one MMSI)
#                            sensors:NAME:MMSI    that vessel's INS/rudder gateway: publishes INS,
#                                                 rudder and speed in its partition only
#                                                 (required: one MMSI)
#                            shore:NAME:M1,M2,..  reads every vessel (PREFIXvessel-*), acknowledges
#                                                 only the vessels listed; shore:NAME:* acknowledges
#                                                 every vessel (required: the list or *)
#                            observer:NAME        reads every vessel, writes nothing
#                          Default: vessel:vessel:257000001 sensors:sensors:257000001 shore:shore:*
#                          observer:observer
#   --partition-prefix P   prefix of the vessel partitions (default none: vessel-<MMSI>); the
#                          processes must then use P + vessel-<MMSI> (sidecar, sensors) and
#                          P + vessel-* (shore, observer)
#   --ca-name NAME         CN of the CA (default "usv-fdi test CA"); a second PKI made with another
#                          name (and OUT) is a foreign CA whose identities must be refused
#   --subject-org ORG      O= of every subject (default "usv-fdi test fleet")
#   --days N               validity of certificates and grants (default 30)
#   --grant-seconds N      the grants expire N seconds from now instead (tests of expiry; the
#                          certificates keep --days)
#   --path-prefix DIR      directory the files will be read from at run time, as written into
#                          security_profiles.xml (default: OUT itself; e.g. /etc/usv-fdi/security
#                          when OUT is mounted there in a container)
#   --initial-peers LIST   comma-separated IPv4 addresses for the _unicast profiles
#   --force                replace an existing OUT
#
# Private keys are written 0600 under OUT and must never be committed: this is a test PKI. A real
# fleet keeps its CA key offline and issues one identity per sidecar, monitor and sensor gateway.
set -euo pipefail
umask 077
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
templates="$root/config/security"

die() { echo "make-security.sh: $*" >&2; exit 2; }

[ $# -ge 1 ] || die "usage: make-security.sh OUT [--identity ROLE:NAME]... (see the header)"
out="$1"
shift
identities=()
ca_name="usv-fdi test CA"
org="usv-fdi test fleet"
days=30
prefix=""
force=0
peers=""
part_prefix=""
grant_seconds=""
while [ $# -gt 0 ]; do
  case "$1" in
    --identity) [ $# -ge 2 ] || die "--identity needs ROLE:NAME"; identities+=("$2"); shift 2 ;;
    --ca-name) [ $# -ge 2 ] || die "--ca-name needs a value"; ca_name="$2"; shift 2 ;;
    --subject-org) [ $# -ge 2 ] || die "--subject-org needs a value"; org="$2"; shift 2 ;;
    --days) [ $# -ge 2 ] || die "--days needs a value"; days="$2"; shift 2 ;;
    --path-prefix) [ $# -ge 2 ] || die "--path-prefix needs a value"; prefix="$2"; shift 2 ;;
    --initial-peers) [ $# -ge 2 ] || die "--initial-peers needs a value"; peers="$2"; shift 2 ;;
    --grant-seconds) [ $# -ge 2 ] || die "--grant-seconds needs a value"; grant_seconds="$2"; shift 2 ;;
    --partition-prefix) [ $# -ge 2 ] || die "--partition-prefix needs a value"; part_prefix="$2"; shift 2 ;;
    --force) force=1; shift ;;
    *) die "unknown option '$1'" ;;
  esac
done
[ ${#identities[@]} -gt 0 ] || identities=(vessel:vessel:257000001 sensors:sensors:257000001 shore:shore:'*' observer:observer)
case "$part_prefix" in *[!A-Za-z0-9_.-]*) die "--partition-prefix may hold only A-Z a-z 0-9 _ . - (not '$part_prefix')" ;; esac
case "$days" in '' | *[!0-9]* | 0) die "--days must be a positive whole number, not '$days'" ;; esac
case "$grant_seconds" in *[!0-9]* | 0) die "--grant-seconds must be a positive whole number, not '$grant_seconds'" ;; esac
peer_list=()
if [ -n "$peers" ]; then
  IFS=, read -r -a peer_list <<<"$peers"
  for a in "${peer_list[@]}"; do
    [[ "$a" =~ ^[0-9]{1,3}(\.[0-9]{1,3}){3}$ ]] || die "--initial-peers: not an IPv4 address: '$a'"
  done
fi
command -v openssl >/dev/null || die "openssl not found (scripts/packages.txt lists it)"
for f in governance.xml permissions.xml.in; do
  [ -r "$templates/$f" ] || die "missing template $templates/$f"
done

# Identities: ROLE:NAME[:VESSELS] with unique names (NAME becomes the certificate's CN and a
# directory). id_role, id_name, id_vessels: parsed, by position.
declare -A seen=()
id_role=()
id_name=()
id_vessels=()
for id in "${identities[@]}"; do
  IFS=: read -r role name vessels extra <<<"$id"
  [ -n "$role" ] && [ -n "${name:-}" ] && [ -z "${extra:-}" ] || die "--identity '$id': expected ROLE:NAME[:VESSELS]"
  case "$role" in vessel | sensors | shore | observer) ;; *) die "--identity '$id': unknown role '$role' (vessel, sensors, shore, observer)" ;; esac
  case "$name" in *[!A-Za-z0-9_.-]*) die "--identity '$id': NAME may hold only A-Z a-z 0-9 _ . -" ;; esac
  [ -z "${seen[$name]:-}" ] || die "--identity '$id': name '$name' given twice"
  seen[$name]=1
  vessels="${vessels:-}"
  case "$role" in
    vessel | sensors)
      [ -n "$vessels" ] || die "--identity '$id': a $role identity is bound to one vessel: give $role:$name:MMSI"
      [[ "$vessels" =~ ^[1-9][0-9]{0,8}$ ]] || die "--identity '$id': '$vessels' is not one MMSI (1..999999999)"
      ;;
    shore)
      [ -n "$vessels" ] || die "--identity '$id': say which vessels the shore may acknowledge: shore:$name:MMSI[,MMSI...] or shore:$name:*"
      if [ "$vessels" != "*" ]; then
        IFS=, read -r -a list <<<"$vessels"
        for m in "${list[@]}"; do
          [[ "$m" =~ ^[1-9][0-9]{0,8}$ ]] || die "--identity '$id': '$m' is not an MMSI (1..999999999)"
        done
      fi
      ;;
    observer) [ -z "$vessels" ] || die "--identity '$id': an observer reads every vessel and writes nothing: give observer:$name" ;;
  esac
  id_role+=("$role")
  id_name+=("$name")
  id_vessels+=("$vessels")
done

case "$(realpath -m "$out")" in / | "$(realpath -m "$root")" | "$(realpath -m "${HOME:-/}")")
  die "refusing to use '$out' as OUT" ;;
esac
if [ -e "$out" ]; then
  [ "$force" -eq 1 ] || die "$out exists (use --force to replace it)"
  rm -rf "$out"
fi
mkdir -p "$out/ca"
out="$(cd "$out" && pwd)"
[ -n "$prefix" ] || prefix="$out"

quiet() { # runs openssl quietly, shows its output only when it fails
  local log
  log="$(mktemp)"
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2
    rm -f "$log"
    die "failed: $*"
  fi
  rm -f "$log"
}

# --- CA ------------------------------------------------------------------------------------
quiet openssl ecparam -name prime256v1 -genkey -noout -out "$out/ca/ca.key"
# digitalSignature: the CA also signs governance and permissions (S/MIME signer purpose).
quiet openssl req -x509 -new -sha256 -key "$out/ca/ca.key" -days "$((days + 1))" \
  -subj "/C=NO/O=$org/CN=$ca_name" \
  -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature" \
  -out "$out/ca/ca.pem"
chmod 0644 "$out/ca/ca.pem"

sign() { # sign FILE.xml -> FILE.p7s (S/MIME, text mode, as the Access-Permissions plugin expects)
  quiet openssl smime -sign -text -in "$1" -out "${1%.xml}.p7s" \
    -signer "$out/ca/ca.pem" -inkey "$out/ca/ca.key"
  chmod 0644 "$1" "${1%.xml}.p7s"
}

cp "$templates/governance.xml" "$out/governance.xml"
sign "$out/governance.xml"

topics() { # topics NAME... -> <topic> elements
  local t
  for t in "$@"; do printf '            <topic>usv_fdi/%s</topic>\n' "$t"; done
}
partition_elems() { # partition_elems PARTITION... -> <partition> elements
  local p
  for p in "$@"; do printf '            <partition>%s</partition>\n' "$p"; done
}
rule() { # rule publish|subscribe "PARTITION..." TOPIC...
  local kind="$1" parts="$2"
  shift 2
  local -a plist
  read -r -a plist <<<"$parts"
  printf '        <%s>\n          <topics>\n%s\n          </topics>\n' "$kind" "$(topics "$@")"
  printf '          <partitions>\n%s\n          </partitions>\n' "$(partition_elems "${plist[@]}")"
  printf '        </%s>\n' "$kind"
}
vessel_partitions() { # vessel_partitions VESSELS -> the partition names (space separated)
  local m out=""
  if [ "$1" = "*" ]; then
    echo "${part_prefix}vessel-*"
    return
  fi
  IFS=, read -r -a list <<<"$1"
  for m in "${list[@]}"; do out="$out ${part_prefix}vessel-$m"; done
  echo "${out# }"
}
allow_rules() { # allow_rules ROLE VESSELS -> the <allow_rule> of the role
  # Partition names are matched by the Access-Permissions plugin as patterns (fnmatch) of the
  # permissions against the partitions an endpoint asks for: a vessel's literal partition allows
  # that partition only (not "vessel-*", not the default partition "").
  local own every
  own="$(vessel_partitions "$2")"
  every="${part_prefix}vessel-*"
  printf '      <allow_rule>\n        <domains>\n          <id_range>\n            <min>0</min>\n            <max>232</max>\n          </id_range>\n        </domains>\n'
  case "$1" in
    vessel) rule publish "$own" fault_event status; rule subscribe "$own" ins rudder speed fault_ack fault_event ;;
    sensors) rule publish "$own" ins rudder speed ;;
    shore) rule publish "$own" fault_ack; rule subscribe "$every" fault_event status ;;
    observer) rule subscribe "$every" fault_event status ;;
  esac
  printf '      </allow_rule>'
}

not_before="$(date -u -d '-1 day' +%Y-%m-%dT%H:%M:%S)"
not_after="$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)"
[ -z "$grant_seconds" ] || not_after="$(date -u -d "+$grant_seconds seconds" +%Y-%m-%dT%H:%M:%S)"

# --- identities ----------------------------------------------------------------------------
profiles="$out/security_profiles.xml"
{
  printf '<?xml version="1.0" encoding="UTF-8" ?>\n'
  printf '<!-- Generated by scripts/make-security.sh: Fast DDS participant profiles with DDS Security\n'
  printf '     (PKI-DH, Access-Permissions, AES-GCM-GMAC) for a TEST PKI. Files are read from %s. -->\n' "$prefix"
  printf '<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">\n  <profiles>\n'
  printf '    <transport_descriptors>\n      <transport_descriptor>\n'
  printf '        <transport_id>usv_fdi_secure_udpv4_loopback</transport_id>\n        <type>UDPv4</type>\n'
  printf '        <interfaceWhiteList>\n          <address>127.0.0.1</address>\n        </interfaceWhiteList>\n'
  printf '      </transport_descriptor>\n      <transport_descriptor>\n'
  printf '        <transport_id>usv_fdi_secure_udpv4</transport_id>\n        <type>UDPv4</type>\n'
  printf '      </transport_descriptor>\n    </transport_descriptors>\n'
} >"$profiles"

security_properties() { # security_properties NAME
  local p="$prefix" n="$1"
  local -a kv=(
    dds.sec.auth.plugin builtin.PKI-DH
    dds.sec.auth.builtin.PKI-DH.identity_ca "file://$p/ca/ca.pem"
    dds.sec.auth.builtin.PKI-DH.identity_certificate "file://$p/$n/cert.pem"
    dds.sec.auth.builtin.PKI-DH.private_key "file://$p/$n/key.pem"
    dds.sec.access.plugin builtin.Access-Permissions
    dds.sec.access.builtin.Access-Permissions.permissions_ca "file://$p/ca/ca.pem"
    dds.sec.access.builtin.Access-Permissions.governance "file://$p/governance.p7s"
    dds.sec.access.builtin.Access-Permissions.permissions "file://$p/$n/permissions.p7s"
    dds.sec.crypto.plugin builtin.AES-GCM-GMAC
  )
  local i
  printf '        <propertiesPolicy>\n          <properties>\n'
  for ((i = 0; i < ${#kv[@]}; i += 2)); do
    printf '            <property>\n              <name>%s</name>\n              <value>%s</value>\n            </property>\n' \
      "${kv[i]}" "${kv[i + 1]}"
  done
  printf '          </properties>\n        </propertiesPolicy>\n'
}

for i in "${!id_role[@]}"; do
  role="${id_role[i]}"
  name="${id_name[i]}"
  vessels="${id_vessels[i]}"
  dir="$out/$name"
  mkdir -p "$dir"
  quiet openssl ecparam -name prime256v1 -genkey -noout -out "$dir/key.pem"
  quiet openssl req -new -sha256 -key "$dir/key.pem" -subj "/C=NO/O=$org/OU=$role/CN=$name" \
    -out "$dir/cert.csr"
  printf 'basicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature,keyAgreement\n' \
    >"$dir/ext.cnf"
  quiet openssl x509 -req -sha256 -in "$dir/cert.csr" -CA "$out/ca/ca.pem" -CAkey "$out/ca/ca.key" \
    -CAcreateserial -days "$days" -extfile "$dir/ext.cnf" -out "$dir/cert.pem"
  rm -f "$dir/cert.csr" "$dir/ext.cnf"
  chmod 0644 "$dir/cert.pem"
  subject="$(openssl x509 -in "$dir/cert.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')"
  allow="$(allow_rules "$role" "$vessels")"
  # Substitute with awk (values may hold '/', '&' or spaces).
  awk -v name="$name" -v subject="$subject" -v nb="$not_before" -v na="$not_after" -v allow="$allow" '
    /^@ALLOW@$/ { print allow; next }
    { gsub(/@NAME@/, name); gsub(/@SUBJECT@/, subject); gsub(/@NOT_BEFORE@/, nb); gsub(/@NOT_AFTER@/, na); print }
  ' "$templates/permissions.xml.in" >"$dir/permissions.xml"
  sign "$dir/permissions.xml"
  printf '%s\n' "$role" >"$dir/role"
  printf '%s\n' "${vessels//,/$'\n'}" >"$dir/vessels"
  chmod 0644 "$dir/role" "$dir/vessels"
  {
    variants=("" _loopback)
    [ ${#peer_list[@]} -eq 0 ] || variants+=(_unicast)
    for variant in "${variants[@]}"; do
      printf '    <participant profile_name="usv_fdi_secure_%s%s">\n      <rtps>\n' "$name" "$variant"
      printf '        <name>usv_fdi_%s</name>\n' "$name"
      if [ "$variant" = _loopback ]; then
        # Same unicast discovery on 127.0.0.1 as usv_fdi_participant_loopback (config/qos).
        printf '        <builtin>\n          <discovery_config>\n            <initialAnnouncements>\n'
        printf '              <count>20</count>\n              <period>\n                <sec>0</sec>\n                <nanosec>100000000</nanosec>\n              </period>\n'
        printf '            </initialAnnouncements>\n          </discovery_config>\n'
        printf '          <initialPeersList>\n            <locator>\n              <udpv4>\n                <address>127.0.0.1</address>\n              </udpv4>\n            </locator>\n          </initialPeersList>\n        </builtin>\n'
        printf '        <userTransports>\n          <transport_id>usv_fdi_secure_udpv4_loopback</transport_id>\n        </userTransports>\n'
        printf '        <useBuiltinTransports>false</useBuiltinTransports>\n'
      fi
      if [ "$variant" = _unicast ]; then
        # SIMPLE discovery also sent by unicast to every address of the fleet (works where
        # multicast does not); UDPv4 only, no SHM.
        printf '        <builtin>\n          <discovery_config>\n            <initialAnnouncements>\n'
        printf '              <count>20</count>\n              <period>\n                <sec>0</sec>\n                <nanosec>100000000</nanosec>\n              </period>\n'
        printf '            </initialAnnouncements>\n          </discovery_config>\n'
        printf '          <initialPeersList>\n'
        for a in "${peer_list[@]}"; do
          printf '            <locator>\n              <udpv4>\n                <address>%s</address>\n              </udpv4>\n            </locator>\n' "$a"
        done
        printf '          </initialPeersList>\n        </builtin>\n'
        printf '        <userTransports>\n          <transport_id>usv_fdi_secure_udpv4</transport_id>\n        </userTransports>\n'
        printf '        <useBuiltinTransports>false</useBuiltinTransports>\n'
      fi
      security_properties "$name"
      printf '      </rtps>\n    </participant>\n'
    done
  } >>"$profiles"
  echo "make-security.sh: $role identity '$name': $subject${vessels:+, vessels $vessels}"
done
rm -f "$out/ca/ca.srl"
printf '  </profiles>\n</dds>\n' >>"$profiles"
chmod 0644 "$profiles"
chmod 0755 "$out" "$out"/*/ 2>/dev/null || true
chmod 0700 "$out/ca"
echo "make-security.sh: test PKI in $out (CA '$ca_name', profiles $profiles)"
