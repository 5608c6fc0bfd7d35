#!/usr/bin/env bash
# Install envmap-studio's desktop integration for this user, from the unpacked bundle:
#   ./install-desktop.sh              menu entry, icon, AppStream metadata, MIME types, and
#                                     envstudio as the default viewer of .exr and .hdr files;
#                                     a link ~/.local/bin/envstudio to this bundle's program
#   ./install-desktop.sh --uninstall  remove all of that again
# Files go under ${XDG_DATA_HOME:-~/.local/share} (applications/, icons/hicolor/, metainfo/,
# mime/packages/); the link under ${ENVSTUDIO_BIN_DIR:-~/.local/bin}. The menu entry starts
# this bundle by its absolute path, so move the bundle first, then run this script. Nothing
# needs root; the desktop's caches are refreshed with update-desktop-database,
# update-mime-database, gtk-update-icon-cache and xdg-mime where they are installed.
set -euo pipefail

APP_ID=io.github.envmapstudio.EnvmapStudio
BUNDLE="$(cd "$(dirname "$0")" && pwd)"
PROGRAM="$BUNDLE/envstudio"
DATA="${XDG_DATA_HOME:-$HOME/.local/share}"
BIN="${ENVSTUDIO_BIN_DIR:-$HOME/.local/bin}"
MIME_TYPES=(image/x-exr image/vnd.radiance)

have() { command -v "$1" >/dev/null 2>&1; }

refresh() {
    have update-desktop-database && update-desktop-database -q "$DATA/applications" || true
    have update-mime-database && update-mime-database "$DATA/mime" >/dev/null 2>&1 || true
    if have gtk-update-icon-cache && [ -f "$DATA/icons/hicolor/index.theme" ]; then
        gtk-update-icon-cache -q -t -f "$DATA/icons/hicolor" || true
    fi
}

uninstall() {
    rm -f "$DATA/applications/$APP_ID.desktop" "$DATA/metainfo/$APP_ID.metainfo.xml" \
        "$DATA/mime/packages/$APP_ID.xml"
    find "$DATA/icons/hicolor" -name "$APP_ID.*" -delete 2>/dev/null || true
    if [ -L "$BIN/envstudio" ] && [ "$(readlink "$BIN/envstudio")" = "$PROGRAM" ]; then
        rm -f "$BIN/envstudio"
    fi
    refresh
    echo "install-desktop: removed envmap-studio's desktop integration from $DATA"
}

install() {
    [ -x "$PROGRAM" ] || { echo "install-desktop: $PROGRAM not found: run me from the bundle" >&2; exit 2; }
    local share="$BUNDLE/share"
    mkdir -p "$DATA/applications" "$DATA/metainfo" "$DATA/mime/packages" "$BIN"
    # the entry names this bundle's program by its absolute path (%f: the file opened)
    sed -e "s|^Exec=envstudio |Exec=\"$PROGRAM\" |" -e "s|^TryExec=envstudio$|TryExec=$PROGRAM|" \
        "$share/applications/$APP_ID.desktop" >"$DATA/applications/$APP_ID.desktop"
    cp "$share/metainfo/$APP_ID.metainfo.xml" "$DATA/metainfo/"
    cp "$share/mime/packages/$APP_ID.xml" "$DATA/mime/packages/"
    (cd "$share/icons" && find hicolor -name "$APP_ID.*" -print0) |
        while IFS= read -r -d '' icon; do
            mkdir -p "$DATA/icons/$(dirname "$icon")"
            cp "$share/icons/$icon" "$DATA/icons/$icon"
        done
    if [ ! -e "$BIN/envstudio" ] || [ -L "$BIN/envstudio" ]; then
        ln -sfn "$PROGRAM" "$BIN/envstudio"
    else
        echo "install-desktop: $BIN/envstudio exists and is not a link; left as it is" >&2
    fi
    refresh
    if have xdg-mime; then
        xdg-mime default "$APP_ID.desktop" "${MIME_TYPES[@]}" || true
    fi
    echo "install-desktop: installed envmap-studio for ${USER:-$(id -un)} ($DATA); .exr and .hdr open in it"
    case ":$PATH:" in
        *":$BIN:"*) ;;
        *) echo "install-desktop: add $BIN to PATH to run envstudio from a terminal" ;;
    esac
}

case "${1:-}" in
    "") install ;;
    --uninstall) uninstall ;;
    -h | --help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//' ;;
    *) echo "install-desktop: unknown option '$1' (expected --uninstall or nothing)" >&2; exit 2 ;;
esac
